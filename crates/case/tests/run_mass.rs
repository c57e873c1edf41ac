//! The consistent mass of a run's model: assembled where the case's scheme
//! reads it (Newmark, consistent by default), left out where it does not
//! (central difference, Newmark with the lumped mass, quasi-static), and a
//! scene without it refused, not misused, by Newmark with the consistent
//! mass.

use std::path::Path;

use stickslip_case::{assemble, assemble_for_run, load};
use stickslip_time::Scheme;

fn case(file: &str, sets: &[&str]) -> stickslip_case::Case {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    load(&root.join(file), &sets).expect("the bundled case loads")
}

#[test]
fn a_run_holds_the_consistent_mass_only_where_its_scheme_reads_it() {
    for (file, sets, wanted) in [
        ("cases/martins-oden/cd-step-eps1e-4.toml", &[][..], false),
        ("cases/martins-oden/newmark-step.toml", &[][..], true),
        (
            "cases/martins-oden/newmark-step.toml",
            &["time.mass=\"lumped\""][..],
            false,
        ),
        ("cases/quasi-static/slab-static-tx300.toml", &[][..], false),
    ] {
        let c = case(file, sets);
        let run = assemble_for_run(&c).expect("assembles");
        assert_eq!(run.model.mass.is_some(), wanted, "{file} {sets:?}");
        // The library's scene keeps M for any scheme, with the same K.
        let any = assemble(&c).expect("assembles");
        assert!(any.model.mass.is_some(), "{file}");
        assert_eq!(any.model.stiffness, run.model.stiffness, "{file}");
        assert_eq!(any.model.lumped_mass, run.model.lumped_mass, "{file}");
    }
}

#[test]
fn newmark_with_the_consistent_mass_refuses_a_scene_without_it() {
    let c = case("cases/martins-oden/cd-step-eps1e-4.toml", &[]);
    let mut scene = assemble_for_run(&c).expect("assembles");
    scene.settings.scheme = Scheme::Newmark {
        beta: 0.25,
        gamma: 0.5,
    };
    let err = scene
        .integrator()
        .expect_err("no consistent mass to run with");
    assert!(err.to_string().contains("consistent mass"), "{err}");
}
