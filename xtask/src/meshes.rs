//! `cargo xtask meshes`: regenerates the committed meshes in `cases/meshes/`
//! with Gmsh's Python API (`cases/meshes/generate.py`), installing the `gmsh`
//! PyPI package first if it is missing. Extra arguments go to the script
//! (e.g. `--out DIR`).

use std::path::Path;

use crate::python;

/// Runs `cases/meshes/generate.py`; it prints one line per file written.
///
/// # Errors
/// gmsh cannot be installed, or the script fails.
pub fn run(root: &Path, args: &[String]) -> Result<(), String> {
    if args.iter().any(|a| a == "-h" || a == "--help") {
        println!("cargo xtask meshes [--out DIR]\n\nRegenerates cases/meshes/*.msh from cases/slab.geo and cases/hole.geo with Gmsh\n(installs the gmsh Python module with pip if it is missing). See cases/meshes/README.md.");
        return Ok(());
    }
    python::ensure_python_modules(&[("gmsh", "gmsh")])?;
    let script = root.join("cases/meshes/generate.py");
    if !script.is_file() {
        return Err(format!(
            "{} is missing; run from a stickslip checkout",
            script.display()
        ));
    }
    println!(
        "writing meshes with {} {}",
        python::python(),
        script.display()
    );
    python::run_script(root, &script, args)
}
