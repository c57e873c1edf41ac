//! `/contact/normal_stress` (docs/results.md): the prescribed pressure
//! p·θ(t) on the paper's law, the foundation's c_n δ on a compliant one;
//! and the same numbers as `OUT.contact.xdmf` shows them (`stickslip
//! views`), read through the XML as a viewer does, where the file holds
//! the dataset, and a valid XML without it where it does not.

mod common;

use std::path::{Path, PathBuf};

use common::{bin, scratch, succeeded};
use stickslip_testkit::case_text::paper_slab_head;

/// Runs `text` into `NAME/out.h5` and returns that file.
fn run(name: &str, text: &str) -> PathBuf {
    let dir = scratch(name);
    let case = dir.join("case.toml");
    std::fs::write(&case, text).unwrap();
    let out = dir.join("out.h5");
    let o = common::run(&case, &out, &["--force", "--quiet"]);
    succeeded(&o, "run");
    out
}

/// (`/time`, `/contact/normal_stress` row by row) of the results file `out`.
fn read(out: &Path) -> (Vec<f64>, Vec<Vec<f64>>) {
    let f = hdf5::File::open(out).unwrap();
    let time = f.dataset("time").unwrap().read_raw::<f64>().unwrap();
    let normal = f
        .dataset("contact/normal_stress")
        .unwrap()
        .read_2d::<f64>()
        .unwrap();
    let rows = normal.rows().into_iter().map(|r| r.to_vec()).collect();
    (time, rows)
}

/// The paper's slab pressed by 300 with the history θ(t) = 1 + t (a table
/// from (0, 1) to (1, 2)), by central difference to t = 0.02 (21 rows).
fn pressure_case() -> String {
    format!(
        r#"{head}[[dirichlet]]
group = "support"
uy = 0.0
[[dirichlet]]
group = "left"
ux = 0.0
[contact]
group = "contact"
pressure = 300.0
pressure_history = {{ table = [[0.0, 1.0], [1.0, 2.0]] }}
mu = 0.3
eps = 1e-2
[time]
scheme = "central_difference"
dt = 1e-3
t_end = 0.02
"#,
        head = paper_slab_head()
    )
}

/// The closed form of [`pressure_case`]: 300·(1 + t) at every node.
fn pressed(t: f64) -> f64 {
    300.0 * (1.0 + t)
}

/// [`pressure_case`]: every node's row is 300·(1 + t), to round-off, in
/// the file and as `OUT.contact.xdmf` shows it at every record.
#[test]
fn a_prescribed_pressure_is_recorded_with_its_history() {
    let out = run("normal-stress-pressure", &pressure_case());
    let (time, rows) = read(&out);
    assert_eq!(time.len(), 21);
    for (t, row) in time.iter().zip(&rows) {
        assert_eq!(row.len(), 16);
        for p in row {
            assert!((p - pressed(*t)).abs() < 1e-9, "t = {t}: {p}");
        }
    }
    let shown = views_normal_stress(&out, 16);
    assert_eq!(shown.len(), 21);
    for (t, values) in shown {
        for p in values {
            assert!((p - pressed(t)).abs() < 1e-9, "record at t = {t}: {p}");
        }
    }
}

/// The slab pressed by 300 on its top onto a floor of c_n = 1e4 from the
/// static preload: at t = 0 every bottom node's c_n δ balances the 300
/// (uniform compression), to 1e-6 of it, and so it stays at every row,
/// the preload an equilibrium of either scheme (Newmark's rows are the
/// traction at the displacement its Newton solve ended at).
#[test]
fn a_compliant_floor_records_its_traction() {
    for scheme in ["central_difference", "newmark"] {
        compliant_floor(scheme);
    }
}

fn compliant_floor(scheme: &str) {
    let text = format!(
        r#"{head}[[dirichlet]]
group = "left"
ux = 0.0
[[traction]]
group = "support"
pressure = 300.0
history = "constant"
[contact]
group = "contact"
law = "compliance"
foundation = {{ point = [0.0, 0.0], normal = [0.0, 1.0] }}
cn = 1e4
mu = 0.3
eps = 1e-3
[time]
scheme = "{scheme}"
dt = 1e-3
t_end = 0.01
"#,
        head = paper_slab_head()
    );
    let out = run(&format!("normal-stress-compliance-{scheme}"), &text);
    let (_, rows) = read(&out);
    assert_eq!(rows.len(), 11, "{scheme}");
    for row in &rows {
        assert_eq!(row.len(), 17);
        for p in row {
            assert!((p - 300.0).abs() < 1e-6 * 300.0, "{scheme}: {row:?}");
        }
    }
    let shown = views_normal_stress(&out, 17);
    assert_eq!(shown.len(), 11, "{scheme}");
    for (t, values) in shown {
        for p in values {
            assert!((p - 300.0).abs() < 1e-6 * 300.0, "{scheme}, t = {t}: {p}");
        }
    }
}

/// One record of `OUT.contact.xdmf` as a viewer reads it: its time, and
/// each node attribute's values, read from the dataset its DataItem names.
struct Record {
    time: f64,
    arrays: Vec<(String, Vec<f64>)>,
}

/// The text between `from` and the next `to` in `s`.
fn between<'a>(s: &'a str, from: &str, to: &str) -> &'a str {
    let (_, rest) = s
        .split_once(from)
        .unwrap_or_else(|| panic!("no {from} in {s}"));
    rest.split_once(to)
        .unwrap_or_else(|| panic!("no {to} after {from}"))
        .0
}

/// Reads the data item `item` (the text from `<DataItem` on) beside the
/// XML in `dir`, as XDMF says: `FILE:PATH` of the stated number type, whose
/// dataset must exist with as many values as its Dimensions state.
fn data_item(dir: &Path, item: &str) -> Vec<f64> {
    let dims: usize = between(item, "Dimensions=\"", "\"")
        .split(' ')
        .map(|d| d.parse::<usize>().unwrap())
        .product();
    let number = (
        between(item, "NumberType=\"", "\""),
        between(item, "Precision=\"", "\""),
    );
    let (file, path) = between(item, "Format=\"HDF\">", "</DataItem>")
        .split_once(':')
        .unwrap();
    let f = hdf5::File::open(dir.join(file)).unwrap();
    let d = f
        .dataset(path)
        .unwrap_or_else(|_| panic!("the XML names {file}:{path}, which is not there"));
    let values: Vec<f64> = match number {
        ("Float", "8") => d.read_raw::<f64>().unwrap(),
        ("Int", "8") => d
            .read_raw::<i64>()
            .unwrap()
            .iter()
            .map(|&v| v as f64)
            .collect(),
        ("Int", "1") => d
            .read_raw::<i8>()
            .unwrap()
            .iter()
            .map(|&v| v as f64)
            .collect(),
        other => panic!("{file}:{path}: number type {other:?}"),
    };
    assert_eq!(values.len(), dims, "{file}:{path}");
    values
}

/// `stickslip views OUT.h5`, then its `OUT.contact.xdmf` read record by
/// record ([`Record`]); every data item, the line's too, must name a
/// dataset of its stated size.
fn contact_xdmf(out: &Path) -> Vec<Record> {
    let o = bin().args(["views", "--quiet"]).arg(out).output().unwrap();
    succeeded(&o, "views");
    let dir = out.parent().unwrap();
    let xml = std::fs::read_to_string(out.with_extension("contact.xdmf")).unwrap();
    let grids: Vec<&str> = xml.split("<Grid Name=\"record ").skip(1).collect();
    grids
        .iter()
        .enumerate()
        .map(|(k, grid)| {
            let grid = grid.split_once("</Grid>").unwrap().0;
            assert!(grid.starts_with(&format!("{k}\"")), "record {k}: {grid}");
            for item in grid.split("<DataItem").skip(1) {
                data_item(dir, item);
            }
            let arrays = grid
                .split("<Attribute Name=\"")
                .skip(1)
                .map(|a| {
                    assert!(a.contains("Center=\"Node\""), "{a}");
                    let name = a.split_once('"').unwrap().0.to_string();
                    (name, data_item(dir, a.split_once("<DataItem").unwrap().1))
                })
                .collect();
            Record {
                time: between(grid, "<Time Value=\"", "\"").parse().unwrap(),
                arrays,
            }
        })
        .collect()
}

/// What `OUT.contact.xdmf` shows as `normal_stress` at each record, (time,
/// values), checked to be the file's own numbers: record k is frame k,
/// its time `/frames/time[k]` and its values row `/frames/row[k]` of
/// `/contact/normal_stress`, bit for bit (the XML and views hold only
/// references), one per node of the `n_c`.
fn views_normal_stress(out: &Path, n_c: usize) -> Vec<(f64, Vec<f64>)> {
    let records = contact_xdmf(out);
    let (_, rows) = read(out);
    let f = hdf5::File::open(out).unwrap();
    let frame_time = f.dataset("frames/time").unwrap().read_raw::<f64>().unwrap();
    let frame_row = f.dataset("frames/row").unwrap().read_raw::<u64>().unwrap();
    assert_eq!(records.len(), frame_time.len());
    records
        .into_iter()
        .enumerate()
        .map(|(k, r)| {
            assert_eq!(r.time.to_bits(), frame_time[k].to_bits(), "record {k}");
            let shown: Vec<&Vec<f64>> = r
                .arrays
                .iter()
                .filter(|(name, _)| name == "normal_stress")
                .map(|(_, v)| v)
                .collect();
            assert_eq!(shown.len(), 1, "record {k}: normal_stress listed once");
            assert_eq!(shown[0].len(), n_c, "record {k}");
            assert_eq!(shown[0], &rows[frame_row[k] as usize], "record {k}");
            (r.time, shown[0].clone())
        })
        .collect()
}

/// A results file of a version before `/contact/normal_stress` (made here
/// by removing it): `views` writes a contact XML that names only datasets
/// that are there, the other fields at every record and no normal stress.
/// A restart of it creates the dataset, its earlier rows 0 (docs/results.md),
/// and `views` then adds its views to the views file it made before and
/// lists it at every record: 0 at the earlier run's rows, 300·(1 + t) at
/// the restart's.
#[test]
fn a_file_without_normal_stress_shows_the_rest_and_gains_it_on_restart() {
    let out = run("normal-stress-older", &pressure_case());
    hdf5::File::open_rw(&out)
        .unwrap()
        .unlink("contact/normal_stress")
        .unwrap();
    let records = contact_xdmf(&out);
    assert_eq!(records.len(), 21);
    for r in &records {
        let names: Vec<&str> = r.arrays.iter().map(|(n, _)| n.as_str()).collect();
        for field in ["s", "friction_stress", "slip_velocity", "state"] {
            assert!(names.contains(&field), "{names:?}");
        }
        assert!(!names.contains(&"normal_stress"), "{names:?}");
    }
    let xml = std::fs::read_to_string(out.with_extension("contact.xdmf")).unwrap();
    assert!(!xml.contains("normal_stress"));
    let views = hdf5::File::open_rw(out.with_extension("views.h5")).unwrap();
    assert!(!views.link_exists("contact/normal_stress"));
    // A mark that stays only if `views` adds to this file, not a new one.
    views
        .new_attr::<u8>()
        .create("mark")
        .unwrap()
        .write_scalar(&7)
        .unwrap();
    drop(views);

    let case = out.with_file_name("case.toml");
    let o = bin()
        .arg("run")
        .arg(&case)
        .arg("--restart")
        .arg(&out)
        .args(["--quiet", "--set", "time.t_end=0.03"])
        .output()
        .unwrap();
    succeeded(&o, "restart");
    let shown = views_normal_stress(&out, 16);
    assert_eq!(shown.len(), 31);
    let views = hdf5::File::open(out.with_extension("views.h5")).unwrap();
    assert_eq!(views.group("contact/normal_stress").unwrap().len(), 31);
    assert_eq!(views.attr("mark").unwrap().read_scalar::<u8>().unwrap(), 7);
    // The restart takes the checkpoint of the state before the last step
    // (docs/results.md), so it writes the rows from t = 0.02 on.
    for (t, values) in shown {
        let want = if t < 0.0195 { 0.0 } else { pressed(t) };
        for p in values {
            assert!(
                (p - want).abs() < 1e-9,
                "record at t = {t}: {p}, not {want}"
            );
        }
    }
}
