//! `stickslip-verify verify [--quick] [--bless] [--only SUITE]` and
//! `stickslip-verify figures [--out DIR]`, run by `cargo xtask verify` and
//! `cargo xtask figures`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use stickslip_verify::{figures, report, verify, Fault, Options, Report};

const USAGE: &str = "\
usage: stickslip-verify verify [--quick] [--bless] [--only SUITE] [--case NAME]... [--fault FAULT]
       stickslip-verify figures [--out DIR]

  verify    closed-form checks, convergence rates, the paper's experiments and
            the reference runs; one row per check, `N passed, M failed,
            K reported` (K: figures shown for the table only), exit 1 on any
            failure or when no check matched
    --quick        the CI subset (under 2 minutes)
    --bless        rewrite cases/reference/*.csv from this build, saying what changed
    --only SUITE   analytic, rates, paper or reference
    --case NAME    only the paper cases whose name contains NAME
    --fault FAULT  inject friction-sign, no-remark-4-2 or wrong-mass into the
                   paper cases (to see the checks catch it)
  figures   the paper's Figs. 3-18 and an energy ledger as PNG and SVG
    --out DIR      output directory (default docs/figures)
";

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("verify/ sits in the workspace")
        .to_path_buf()
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.split_first() {
        Some((c, rest)) if c == "verify" => match parse_verify(rest) {
            Ok(opts) => run_verify(&opts),
            Err(e) => usage_error(&e),
        },
        Some((c, rest)) if c == "figures" => {
            let out = match rest {
                [] => root().join("docs/figures"),
                [flag, dir] if flag == "--out" => PathBuf::from(dir),
                _ => return usage_error(&format!("figures: unexpected arguments {rest:?}")),
            };
            match figures::draw_all(&root(), &out) {
                Ok(files) => {
                    for f in files {
                        println!("wrote {}", f.display());
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("stickslip-verify figures: {e}");
                    ExitCode::FAILURE
                }
            }
        }
        Some((h, _)) if h == "--help" || h == "-h" || h == "help" => {
            print!("{USAGE}");
            ExitCode::SUCCESS
        }
        _ => usage_error("say verify or figures"),
    }
}

fn usage_error(e: &str) -> ExitCode {
    eprintln!("stickslip-verify: {e}\n{USAGE}");
    ExitCode::from(2)
}

fn parse_verify(args: &[String]) -> Result<Options, String> {
    let mut o = Options::default();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = |flag: &str| it.next().cloned().ok_or(format!("{flag} needs a value"));
        match a.as_str() {
            "--quick" => o.quick = true,
            "--bless" => o.bless = true,
            "--only" => o.only = Some(value("--only")?),
            "--case" => o.cases.push(value("--case")?),
            "--fault" => o.fault = Some(Fault::parse(&value("--fault")?)?),
            other => return Err(format!("verify: unknown argument {other:?}")),
        }
    }
    Ok(o)
}

fn run_verify(opts: &Options) -> ExitCode {
    let start = Instant::now();
    let mut r = Report::new(true);
    if !opts.bless {
        println!("{}", report::header());
    }
    if let Err(e) = verify(&root(), opts, &mut r) {
        eprintln!("stickslip-verify: {e}");
        return ExitCode::from(2);
    }
    let failed: Vec<_> = r.rows.iter().filter(|x| !x.pass).collect();
    if !failed.is_empty() {
        println!("\nfailed checks:");
        for f in &failed {
            println!("{}", report::format_row(f));
        }
    }
    eprintln!("verify: {:.1} s", start.elapsed().as_secs_f64());
    println!("{}", r.summary());
    if !opts.bless && r.rows.is_empty() {
        // A run of no checks proves nothing (lib.rs refuses the ways known
        // to lead here; this guards any other).
        eprintln!(
            "stickslip-verify: no checks matched (--only {}, --case {:?})",
            opts.only.as_deref().unwrap_or("(all)"),
            opts.cases
        );
        return ExitCode::FAILURE;
    }
    if r.failed() == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
