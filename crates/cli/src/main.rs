//! The `stickslip` command: 2-D linear elastodynamics with regularized
//! Coulomb friction (Martins & Oden 1983).
//!
//! This file is the command line only; the work is in the `stickslip`
//! library (case files, HDF5 results, runs; see `lib.rs`).
//!
//! Exit codes: 0 success; 2 bad input (case, mesh, arguments — clap's usage
//! errors exit 2 too); 1 a run that failed after it started (the file keeps
//! every step written), or a command's text that could not be written to
//! stdout or stderr through `console` (a full disk behind a redirection:
//! what the command wrote to files is kept; `run --json` whose summary is
//! lost keeps its complete file); 130 interrupted by SIGINT, SIGTERM or
//! SIGHUP (the file is valid and holds a checkpoint to `--restart` from).
//! What `run` writes on stderr (progress, warnings, its summary) and
//! `stress`'s progress lines are written with `say!`, whose failures are
//! ignored, as are those of the `error:` lines of `report`: they change
//! no exit code. A closed pipe (`| head`) ends the commands other than
//! `run` quietly, by SIGPIPE.

// The system calls are in the library's `sys` module.
#![forbid(unsafe_code)]

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use stickslip::console::{self, WriteError};
use stickslip::{advise, check_cmd, mesh_cmd, probe, run, views_cmd};
use stickslip_case as case;
use stickslip_case::InputError;

#[derive(Debug, Parser)]
#[command(
    name = "stickslip",
    version,
    about = "2-D elastodynamics with Coulomb friction (Martins & Oden 1983)",
    after_help = "Examples:\n  stickslip mesh cases/meshes/slab-q2-8x2.msh\n  stickslip check cases/martins-oden/cd-step-eps1e-4.toml\n  stickslip run cases/martins-oden/cd-step-eps1e-4.toml -o slab.h5 --set time.dt=5e-4\n  stickslip views slab.h5\n  stickslip probe slab.h5 --at 8,0 --field ux"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a case and write the results to HDF5.
    #[command(
        after_help = "Example:\n  stickslip run case.toml -o out.h5 --set time.dt=5e-4 --set contact.eps=1e-2\n\n\
Exit codes: 0 complete, 1 the run failed midway (the file keeps every step written, complete = false) \
or its --json summary could not be written to stdout (the file is complete), 2 bad input, 130 interrupted by SIGINT, SIGTERM or SIGHUP (the file is valid, complete = false; continue it with --restart OUT.h5).\n\n\
A second Ctrl-C while the first is being handled, a quarter second or more after it, exits at once (the file keeps every step up to its last flush)."
    )]
    Run {
        /// The case file (TOML).
        case: PathBuf,
        /// Results file (default: output.file of the case, relative to the case file).
        #[arg(short, long, value_name = "OUT.h5")]
        output: Option<PathBuf>,
        /// Override a case value by its dotted path, e.g. time.scheme=newmark (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Overwrite an existing results file.
        #[arg(long)]
        force: bool,
        /// No progress (a bar on a terminal, a line a minute in a log) and no
        /// summary; warnings are still printed (and kept in the results file).
        #[arg(short, long)]
        quiet: bool,
        /// Print the closing summary as one JSON object on stdout.
        #[arg(long)]
        json: bool,
        /// Continue the run saved in this results file from its last
        /// checkpoint, appending to it (t_end may grow, output settings may
        /// change; physics and discretization must be as stored in the file).
        #[arg(long, value_name = "OUT.h5", conflicts_with_all = ["output", "force"])]
        restart: Option<PathBuf>,
    },
    /// Validate a case and print the model size, the critical time step and the solver; no run.
    #[command(after_help = "Example:\n  stickslip check case.toml --set time.scheme=newmark")]
    Check {
        /// The case file (TOML).
        case: PathBuf,
        /// Override a case value by its dotted path (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
    },
    /// Describe a Gmsh .msh file: format, counts by element type, physical groups, bounding box.
    #[command(after_help = "Example:\n  stickslip mesh cases/meshes/slab-q2-8x2.msh --json")]
    Mesh {
        /// The mesh file (MSH 2.2 or 4.1, ASCII or binary).
        file: PathBuf,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Choose the cheapest element order, mesh of mesh.ladder, scheme, dt and eps whose
    /// estimated error on one output is below a tolerance (measured by pilot runs of the case).
    #[command(
        after_help = "Example:\n  stickslip advise cases/martins-oden/cd-step-eps1e-4.toml --tol 1e-2 --on ux --at 8,1 --write slab-1e-2.toml\n\n\
Exit codes: 0 a configuration meets the tolerance (estimated), 1 none of the ladder does or a pilot run failed, 2 bad input."
    )]
    Advise {
        /// The case file (TOML) with mesh.ladder.
        case: PathBuf,
        /// Relative error to reach, between 0 and 1: L2 in time over [0, t_end] of the
        /// difference, relative to the motion since t = 0 (ux, uy: ‖u − u_ref‖ / ‖u_ref − u_ref(0)‖),
        /// to the history (friction_stress), or |ΔE(t_end)| / |E(t_end) − E(0)| (energy).
        #[arg(long, value_name = "X", allow_negative_numbers = true)]
        tol: f64,
        /// The output the tolerance is on: ux, uy, friction_stress or energy.
        #[arg(long, value_name = "QUANTITY")]
        on: String,
        /// The point X,Y; the nearest node (contact node for friction_stress) is used.
        #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
        at: Option<String>,
        /// Write the case with the chosen configuration here (comments kept).
        #[arg(long, value_name = "OUT.toml")]
        write: Option<PathBuf>,
        /// Print one JSON object on stdout instead of the report.
        #[arg(long)]
        json: bool,
    },
    /// Write a finished run's stress fields (/stress, /von_mises) into OUT.stress.h5 beside its
    /// results file, and the viewers' files as `views` does, OUT.xdmf listing the stresses.
    #[command(after_help = "Example:\n  stickslip stress slab.h5")]
    Stress {
        /// A results file written by `stickslip run` (no run may be writing it).
        file: PathBuf,
        /// No progress lines.
        #[arg(short, long)]
        quiet: bool,
    },
    /// Write OUT.xdmf, OUT.contact.xdmf and OUT.views.h5 beside a results file, for ParaView,
    /// meshio and PyVista (the run itself does not: their cost grows with the records).
    #[command(after_help = "Example:\n  stickslip views slab.h5\n\n\
Open slab.xdmf in ParaView (any of its XDMF readers) and slab.contact.xdmf for the friction and normal stresses along \
the contact surface; meshio.xdmf.TimeSeriesReader and pyvista.read read them too. Works on a finished, \
interrupted or failed run's file; run it again after a --restart (it adds the new records).")]
    Views {
        /// A results file written by `stickslip run` (no run may be writing it).
        file: PathBuf,
        /// No summary line (notes are still printed).
        #[arg(short, long)]
        quiet: bool,
    },
    /// Print the time history of one field at the node nearest to a point, or one field along a
    /// boundary group at given times (--along).
    #[command(
        after_help = "Examples:\n  stickslip probe slab.h5 --at 8,0 --field ux --csv > node81.csv\n  \
stickslip probe slab.h5 --along contact --times 0.1,0.5 --field friction_stress -o contact.csv\n\n\
-o refuses an existing file unless --force is given, and never writes over the results file it reads."
    )]
    Probe {
        /// A results file written by `stickslip run`.
        file: PathBuf,
        /// The point X,Y; the nearest node is used.
        #[arg(
            long,
            value_name = "X,Y",
            allow_hyphen_values = true,
            required_unless_present = "along"
        )]
        at: Option<String>,
        /// The field to print.
        #[arg(long, value_enum, default_value_t = probe::Field::Ux)]
        field: probe::Field,
        /// Comma-separated values with a header line instead of a table.
        #[arg(long)]
        csv: bool,
        /// With --along -o FILE: overwrite FILE if it exists (never the results file read).
        #[arg(long)]
        force: bool,
        #[command(flatten)]
        along: probe::AlongArgs,
    },
}

/// Prints each line of a message as `error: ...` on stderr.
fn report(msg: &str) {
    use std::io::Write;
    let mut err = std::io::stderr().lock();
    for line in msg.lines() {
        // A closed stderr must not turn the exit code into a panic's 101.
        let _ = writeln!(err, "error: {line}");
    }
}

/// Exit code for text that could not be written to stdout or stderr: 1,
/// said on stderr unless the reader closed the pipe (or stderr is what
/// failed: `report` then fails too, quietly).
fn write_failed(e: &WriteError) -> ExitCode {
    if !e.broken_pipe() {
        report(&e.to_string());
    }
    ExitCode::from(1)
}

/// Exit code for an error from a run or a check: 2 for bad input, else 1.
fn fail(e: &anyhow::Error) -> ExitCode {
    if let Some(input) = e.downcast_ref::<InputError>() {
        report(&input.0);
        ExitCode::from(2)
    } else if let Some(w) = e.downcast_ref::<WriteError>() {
        write_failed(w)
    } else {
        report(&format!("{e:#}"));
        ExitCode::from(1)
    }
}

fn main() -> ExitCode {
    stickslip::sys::keep_freed_memory();
    let cli = Cli::parse();
    if !matches!(cli.command, Command::Run { .. }) {
        // Writing to a closed pipe ends the process quietly, as other Unix
        // tools do (`stickslip probe ... | head` panicked on the broken
        // pipe, exit 101). Not for `run`, which must write its results
        // whatever becomes of its stderr: it writes its messages without
        // panicking.
        stickslip::sys::default_sigpipe();
    }
    match cli.command {
        Command::Run {
            case,
            output,
            sets,
            force,
            quiet,
            json,
            restart,
        } => {
            let case_path = case;
            let case = match case::load(&case_path, &sets) {
                Ok(c) => c,
                Err(e) => {
                    report(&e.0);
                    return ExitCode::from(2);
                }
            };
            // The case's output.file, where no -o replaces it: its line is
            // where to change it.
            let at_case = restart.is_none() && output.is_none();
            let out = match &restart {
                Some(r) => r.clone(),
                None => output.unwrap_or_else(|| case.output.file.clone()),
            };
            if restart.is_none() {
                if let Err(e) = stickslip::results_file::check_output(
                    &out,
                    &stickslip::results_file::case_inputs(&case),
                    force,
                ) {
                    if at_case {
                        report(&format!("{}output.file: {}", case.at("output.file"), e.0));
                    } else {
                        report(&e.0);
                    }
                    return ExitCode::from(2);
                }
            } else if let Err(e) = stickslip::results_file::check_restart(&out) {
                report(&e.0);
                return ExitCode::from(2);
            } else if stickslip::results_file::in_use(&out) {
                report(&format!(
                    "--restart {}: the file is open in another process (a run still writing it, \
                     or a reader such as h5py or ParaView); wait for it or close it",
                    out.display()
                ));
                return ExitCode::from(2);
            }
            let stop = match run::StopFlags::install() {
                Ok(s) => s,
                Err(e) => {
                    report(&format!(
                        "cannot install the SIGINT/SIGTERM/SIGHUP handlers: {e}"
                    ));
                    return ExitCode::from(1);
                }
            };
            let options = run::RunOptions {
                quiet,
                json,
                restart: restart.is_some(),
                stop,
                sets,
            };
            match run::execute(&case, &out, &options) {
                Ok(run::Outcome::Complete) => ExitCode::SUCCESS,
                Ok(run::Outcome::Failed) => ExitCode::from(1),
                Ok(run::Outcome::Interrupted) => ExitCode::from(130),
                Ok(run::Outcome::SummaryLost) => ExitCode::from(1),
                Err(e) => fail(&e),
            }
        }
        Command::Check { case, sets } => {
            let case = match case::load(&case, &sets) {
                Ok(c) => c,
                Err(e) => {
                    report(&e.0);
                    return ExitCode::from(2);
                }
            };
            match check_cmd::check(&case).map(|text| console::out(&text)) {
                Ok(Ok(())) => ExitCode::SUCCESS,
                Ok(Err(w)) => write_failed(&w),
                Err(e) => fail(&e),
            }
        }
        Command::Advise {
            case,
            tol,
            on,
            at,
            write,
            json,
        } => {
            let parsed = advise::Quantity::parse(&on)
                .map_err(InputError)
                .and_then(|q| {
                    let at = at.as_deref().map(advise::parse_point).transpose()?;
                    Ok((q, at))
                });
            let (quantity, at) = match parsed {
                Ok(p) => p,
                Err(e) => {
                    report(&e.0);
                    return ExitCode::from(2);
                }
            };
            let case = match case::load(&case, &[]) {
                Ok(c) => c,
                Err(e) => {
                    report(&e.0);
                    return ExitCode::from(2);
                }
            };
            let options = advise::Options {
                tol,
                quantity,
                at,
                write,
                json,
            };
            match advise::command(&case, &options) {
                Ok(advise::Verdict::Found) => ExitCode::SUCCESS,
                Ok(advise::Verdict::NotReachable) => ExitCode::from(1),
                Err(e) => fail(&e),
            }
        }
        Command::Stress { file, quiet } => match stickslip::stress_cmd::command(&file, quiet) {
            Ok((rows, nodes, written)) => {
                let mut said = Ok(());
                if !quiet {
                    said = console::err(&format!(
                        "stress: {rows} records of {nodes} nodes into {} (/stress, /von_mises), listed in {}\n",
                        stickslip::stress_cmd::stress_path(&file).display(),
                        stickslip::xdmf::xdmf_path(&file).display()
                    ));
                }
                if let Some(note) = &written.note {
                    said = said.and(console::err(&format!("stress: note: {note}\n")));
                }
                said.map_or_else(|w| write_failed(&w), |()| ExitCode::SUCCESS)
            }
            Err(e) => fail(&e),
        },
        Command::Views { file, quiet } => match views_cmd::command(&file) {
            Ok(written) => {
                let mut said = Ok(());
                if !quiet {
                    said = console::err(&format!("{}\n", views_cmd::summary(&file, &written)));
                }
                if let Some(note) = &written.note {
                    said = said.and(console::err(&format!("views: note: {note}\n")));
                }
                said.map_or_else(|w| write_failed(&w), |()| ExitCode::SUCCESS)
            }
            Err(e) => fail(&e),
        },
        Command::Mesh { file, json } => match mesh_cmd::report(&file, json) {
            Ok(text) => {
                let end = if json { "\n" } else { "" };
                match console::out(&format!("{text}{end}")) {
                    Ok(()) => ExitCode::SUCCESS,
                    Err(w) => write_failed(&w),
                }
            }
            Err(e) => {
                report(&e.0);
                ExitCode::from(2)
            }
        },
        Command::Probe {
            file,
            at,
            field,
            csv,
            force,
            along,
        } => match at {
            None => match probe::write_along(&file, &along, field, force) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => fail(&e),
            },
            // clap's `requires` does not hold across the flattened group.
            Some(_) if along.output.is_some() || along.times.is_some() || force => {
                report(
                    "probe: -o, --times and --force go with --along GROUP; with --at the history goes to \
                     stdout (redirect it: > FILE)",
                );
                ExitCode::from(2)
            }
            Some(at) => match probe::probe(&file, &at, field, csv) {
                Ok(p) => {
                    let info = if csv {
                        console::err(&p.info)
                    } else {
                        console::out(&p.info)
                    };
                    // The history even where the note on stderr failed.
                    let table = console::out(&p.table);
                    info.and(table)
                        .map_or_else(|w| write_failed(&w), |()| ExitCode::SUCCESS)
                }
                Err(e) => {
                    report(&e.0);
                    ExitCode::from(2)
                }
            },
        },
    }
}
