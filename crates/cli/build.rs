//! Links HDF5 statically where the system has its static library.
//!
//! hdf5-metno-sys asks the linker for `-lhdf5` and finds the shared
//! library, which Debian builds with its S3 driver: loading it loads
//! libcurl, OpenSSL, GnuTLS, Kerberos and LDAP, whose relocations are
//! most of a small run's start-up (docs/performance.md). The static archive
//! (Debian's libhdf5-dev ships it) brings only the objects we call, and
//! those need no network library; only its compression filters need zlib
//! and szip (libaec), linked statically too.
//!
//! How: a directory of our own, searched before hdf5-metno-sys's (Cargo
//! passes a package's own search paths before its dependencies'), holds a
//! `libhdf5.a` that is a linker script naming the archives. `-lhdf5` then
//! finds it, and the group resolves in place, whatever the order of the
//! other libraries on the line.
//!
//! Where any archive is missing (another system, HDF5 built by hand), or
//! with `STICKSLIP_HDF5_LINK=dynamic`, nothing is done: the shared library
//! is linked as before.

use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-env-changed=STICKSLIP_HDF5_LINK");
    println!("cargo::rerun-if-env-changed=HDF5_DIR");
    // For the test that checks what the binary loads.
    let how = if link_static() { "static" } else { "dynamic" };
    println!("cargo::rustc-env=STICKSLIP_HDF5_LINKED={how}");
}

/// Puts the linker script in place, if the archives are there and no one
/// asked for the shared library; whether it did.
fn link_static() -> bool {
    if env::var("STICKSLIP_HDF5_LINK").is_ok_and(|v| v == "dynamic") {
        return false;
    }
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("linux") {
        return false;
    }
    let Some(hdf5) = hdf5_archive() else {
        println!("cargo::warning=no static libhdf5.a found: HDF5 is linked as a shared library (slower start-up)");
        return false;
    };
    let mut archives = vec![hdf5];
    for name in ["libsz.a", "libaec.a", "libz.a"] {
        match compiler_file(name) {
            Some(p) => archives.push(p),
            None => {
                println!("cargo::warning=no {name} found: HDF5 is linked as a shared library (slower start-up)");
                return false;
            }
        }
    }
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("Cargo sets OUT_DIR"));
    let dir = out.join("hdf5-static");
    std::fs::create_dir_all(&dir).expect("OUT_DIR is writable");
    let list: Vec<String> = archives
        .iter()
        .map(|p| format!("\"{}\"", p.display()))
        .collect();
    let script = format!("GROUP ( {} )\n", list.join(" "));
    std::fs::write(dir.join("libhdf5.a"), script).expect("OUT_DIR is writable");
    for p in &archives {
        println!("cargo::rerun-if-changed={}", p.display());
    }
    println!("cargo::rustc-link-search=native={}", dir.display());
    true
}

/// The static HDF5 beside the shared one the build finds: `HDF5_DIR/lib`,
/// pkg-config's directories (Debian's `hdf5/serial`), the compiler's.
fn hdf5_archive() -> Option<PathBuf> {
    let mut dirs: Vec<PathBuf> = Vec::new();
    if let Some(root) = env::var_os("HDF5_DIR") {
        dirs.push(Path::new(&root).join("lib"));
    } else if let Ok(o) = Command::new("pkg-config")
        .args(["--libs-only-L", "hdf5"])
        .output()
    {
        if o.status.success() {
            let text = String::from_utf8_lossy(&o.stdout).into_owned();
            dirs.extend(
                text.split_whitespace()
                    .filter_map(|w| w.strip_prefix("-L"))
                    .map(PathBuf::from),
            );
        }
    }
    dirs.iter()
        .map(|d| d.join("libhdf5.a"))
        .find(|p| p.is_file())
        .or_else(|| {
            // A user's HDF5_DIR without the archive is not replaced by the
            // system's.
            env::var_os("HDF5_DIR")
                .is_none()
                .then(|| compiler_file("libhdf5.a"))
                .flatten()
        })
}

/// Where the C compiler (the linker rustc calls) finds `name` on its
/// search path, if it does.
fn compiler_file(name: &str) -> Option<PathBuf> {
    let cc = env::var("CC").unwrap_or_else(|_| "cc".into());
    let o = Command::new(cc)
        .arg(format!("-print-file-name={name}"))
        .output()
        .ok()?;
    let p = PathBuf::from(String::from_utf8_lossy(&o.stdout).trim());
    // Not found: gcc and clang print the bare name.
    (p.is_absolute() && p.is_file()).then_some(p)
}
