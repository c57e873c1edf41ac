//! Debian packages for the set-up: apt-get, as root or through sudo.

use std::process::Command;

use crate::run;

/// Debian's apt-get, through sudo unless root; the package lists are
/// updated once, before the first install.
#[derive(Default)]
pub(crate) struct Apt {
    updated: bool,
}

impl Apt {
    fn command(args: &[&str]) -> Command {
        let mut c = if is_root() {
            Command::new("apt-get")
        } else {
            let mut c = Command::new("sudo");
            c.arg("apt-get");
            c
        };
        c.args(args).env("DEBIAN_FRONTEND", "noninteractive");
        c
    }

    pub(crate) fn install(&mut self, packages: &[&str]) -> Result<(), String> {
        if !self.updated {
            run(&mut Self::command(&["update", "-q"]))?;
            self.updated = true;
        }
        run(Self::command(&["install", "-y", "-q"]).args(packages))
    }
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false)
}
