//! `stickslip-study chart|stability [--quick] [--out DIR]`.

use std::path::PathBuf;
use std::process::ExitCode;

const USAGE: &str = "usage: stickslip-study <chart|stability> [--quick] [--out DIR]";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match real_main(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("stickslip-study: {e}");
            ExitCode::FAILURE
        }
    }
}

fn real_main(args: &[String]) -> Result<(), String> {
    let Some((cmd, rest)) = args.split_first() else {
        return Err(USAGE.into());
    };
    let mut quick = false;
    let mut out = None;
    let mut it = rest.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quick" => quick = true,
            "--out" => {
                out =
                    Some(PathBuf::from(it.next().ok_or_else(|| {
                        format!("--out needs a directory\n{USAGE}")
                    })?))
            }
            other => return Err(format!("unknown argument {other:?}\n{USAGE}")),
        }
    }
    // The smoke test must not overwrite the committed figures.
    let out = out.unwrap_or_else(|| {
        let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
        if quick {
            root.join("target/study-quick")
        } else {
            root.join("docs")
        }
    });
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    match cmd.as_str() {
        "chart" => stickslip_study::chart::main(&out, quick),
        "stability" => stickslip_study::stability::main(&out, quick),
        _ => Err(USAGE.into()),
    }
}
