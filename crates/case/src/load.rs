//! Reading a case: TOML in, a validated [`Case`] out (DESIGN.md "Case file").
//!
//! Loading goes in five steps, so that every message can name the file and
//! the line the user has to edit:
//! 1. parse the text with `toml_edit` (syntax errors, original lines);
//! 2. apply the `--set KEY=VALUE` overrides to that document, which keeps the
//!    rest of the text (and its comments) as written; the result is
//!    [`Case::source`], the case as run;
//! 3. check every key against the schema (`keys.rs`): unknown keys (with
//!    the nearest valid key suggested) and values of the wrong type are
//!    all collected, then removed so that step 4 can still look at the rest;
//! 4. deserialize with serde into the schema's types (`deny_unknown_fields`);
//! 5. validate every value, collecting all problems before reporting, each
//!    at the place of its value in the text.
//!
//! Lines of the final text are mapped back to the user's file by a line diff;
//! a problem on a line that `--set` changed is reported against that `--set`.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;

use crate::error::{listed, InputError};
use crate::keys::{check_table, dotted, remove_path, seg_name, stood_for, value_spans};
use crate::locate::{line_col, Locator};
use crate::schema::{Case, ContactLaw, History, MassKind, Mu, Scheme, ROOT};
use crate::set::{apply_set, field_rule};

/// The shortest reduced step (`time.stick_reduction.dt`) as a fraction of
/// `time.dt`. Newmark's energy balance on the paper's slab (Δt = 1e-3,
/// energy about 336) with reduced steps of this fraction of Δt: 4e-10 at
/// 1e-5, 9e-7 at 1e-9, 7e-3 at 1e-12, 81 at 1e-15, and at 1e-17 the
/// energy grew to 8e13 while the run went on to its end
/// (docs/case-file.md).
pub const REDUCTION_MIN_RATIO: f64 = 1e-9;

/// Reads, overrides (`--set KEY=VALUE`, VALUE parsed as TOML, else taken as a
/// string) and validates a case file.
///
/// # Errors
/// An [`InputError`] listing every problem found, each as
/// `file:line:col: what; what to do` (or `--set KEY=VALUE: ...`).
pub fn load(path: &Path, sets: &[String]) -> Result<Case, InputError> {
    let file = path.display().to_string();
    // A device or FIFO would be read forever (`check /dev/zero` would
    // hang); a directory's read error ("Is a directory") says nothing of
    // what to give.
    match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => {
            return Err(InputError(format!(
                "{file} is a directory; give the case's .toml file in it"
            )))
        }
        Ok(m) if !m.is_file() => {
            return Err(InputError(format!(
                "{file}: not a regular file (a device, FIFO or socket); give the case's .toml file"
            )))
        }
        _ => {}
    }
    let bytes = std::fs::read(path).map_err(|e| {
        InputError(format!(
            "{file}: cannot read the case file: {e}; check the path"
        ))
    })?;
    if bytes.starts_with(&[0xff, 0xfe]) || bytes.starts_with(&[0xfe, 0xff]) {
        return Err(InputError(format!(
            "{file}: UTF-16 text (it starts with a UTF-16 byte-order mark); TOML files are UTF-8: \
             save it as UTF-8 in your editor (e.g. `iconv -f utf-16 -t utf-8`)"
        )));
    }
    let original = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let text = &e.as_bytes()[..at];
        let line = text.iter().filter(|&&b| b == b'\n').count() + 1;
        let col = text.iter().rev().take_while(|&&b| b != b'\n').count() + 1;
        InputError(format!(
            "{file}:{line}:{col}: not UTF-8 text (byte {at}); TOML files are UTF-8: save it as \
             UTF-8 in your editor (e.g. `iconv -f latin1 -t utf-8`)"
        ))
    })?;
    load_str(path, &original, sets)
}

/// [`load`] on text already in memory (`path` names it and anchors relative paths).
///
/// # Errors
/// As [`load`].
pub fn load_str(path: &Path, original: &str, sets: &[String]) -> Result<Case, InputError> {
    let file = path.display().to_string();
    let mut doc: toml_edit::DocumentMut = original.parse().map_err(|e: toml_edit::TomlError| {
        let at = e.span().map(|s| line_col(original, s.start));
        InputError(format!(
            "{}: invalid TOML: {}; fix the syntax there",
            at.map_or(file.clone(), |(l, c)| format!("{file}:{l}:{c}")),
            e.message().trim_end()
        ))
    })?;
    // A --set of one rule for the fields replaces the file's (apply_set),
    // but two different ones on one command line contradict each other as
    // two in a file do: refused, not the last taken.
    let mut rule: Option<(&str, &String)> = None;
    for s in sets {
        if let Some(r) = field_rule(s) {
            if let Some((first, by)) = rule.filter(|(first, _)| *first != r) {
                return Err(InputError(format!(
                    "--set {s}: output.{r} and output.{first} (--set {by}) both say when the \
                     fields are written; keep one of them (frames: N over [0, t_end], interval: \
                     simulated time between frames, every: N steps)"
                )));
            }
            rule = Some((r, s));
        }
        apply_set(&mut doc, s).map_err(|m| InputError(format!("--set {s}: {m}")))?;
    }
    let source = if sets.is_empty() {
        original.to_string()
    } else {
        doc.to_string()
    };
    // Step 3: every key against the schema, all problems at once; keys that
    // are unknown or of the wrong type are then removed so that serde and
    // the value checks can still report on the rest.
    let loc = Locator::new(&file, original, &source, sets, false);
    let mut problems = Vec::new();
    let mut removals = Vec::new();
    let mut typed = Vec::new();
    match toml_edit::Document::parse(source.as_str()) {
        Ok(spanned) => check_table(
            spanned.as_table(),
            &mut Vec::new(),
            ROOT,
            &mut |span, msg| problems.push(format!("{}: {msg}", loc.at(span))),
            &mut removals,
            &mut typed,
        ),
        Err(e) => {
            // Only --set can make the text unparsable here (the original parsed).
            return Err(InputError(format!(
                "{}: the case after --set is not valid TOML: {}; check the --set values",
                file,
                e.message().trim_end()
            )));
        }
    }
    // Lines whose value was replaced: later problems there are artefacts.
    let quiet_lines: Vec<String> = typed
        .iter()
        .filter_map(|(_, _, span)| {
            let at = loc.at(span.clone());
            at.rsplit_once(':').map(|(l, _)| format!("{l}:"))
        })
        .filter(|l| !l.starts_with("--set"))
        .collect();
    let cleaned = if removals.is_empty() && typed.is_empty() {
        None
    } else {
        let mut doc: toml_edit::DocumentMut =
            source.parse().map_err(|e: toml_edit::TomlError| {
                InputError(format!("{file}: {}", e.message().trim_end()))
            })?;
        for r in &removals {
            remove_path(doc.as_table_mut(), r, None);
        }
        for (r, with, _) in &typed {
            remove_path(doc.as_table_mut(), r, with.as_ref());
            if with.is_none() {
                removals.push(r.clone());
            }
        }
        Some(doc.to_string())
    };
    let text = cleaned.as_deref().unwrap_or(&source);
    let loc_text = Locator::new(&file, original, text, sets, cleaned.is_some());

    match toml::from_str::<Case>(text) {
        Err(e) => {
            let msg = e.message().trim_end().to_string();
            // A required key removed above for its type is already
            // reported, and so is an unknown key that stood for it.
            let missing = msg
                .strip_prefix("missing field `")
                .and_then(|m| m.split_once('`'))
                .map(|(k, _)| k);
            let removed_leaf = |m: &str| {
                removals.iter().any(|r| {
                    r.last()
                        .is_some_and(|k| m.contains(&format!("`{}`", seg_name(k))))
                        || missing.is_some_and(|k| stood_for(r, k))
                })
            };
            if !(msg.starts_with("missing field") && removed_leaf(&msg)) {
                let hint = if let Some(key) = history_at(text, e.span()) {
                    history_forms(&key)
                } else if msg.starts_with("unknown field") {
                    "; check the spelling (docs/case-file.md lists the keys)".into()
                } else if msg.starts_with("missing field") {
                    "; add it (docs/case-file.md lists the keys)".into()
                } else if msg.contains("variant") {
                    "; use one of the values listed".into()
                } else if msg.starts_with("invalid type") || msg.starts_with("invalid length") {
                    "; numbers go without quotes, text in quotes, vectors as [x, y]".into()
                } else {
                    String::new()
                };
                problems.push(format!("{}: {msg}{hint}", loc_text.at(e.span())));
            }
        }
        Ok(case) => {
            // Where each value is, in the text serde read.
            let spans = spans_in(text);
            // Keys whose value was reported and replaced or removed.
            let placeholders: Vec<String> = typed.iter().map(|(p, _, _)| dotted(p)).collect();
            match complete(case, path, source.clone(), &spans, &loc_text, &placeholders) {
                Ok(case) if problems.is_empty() => return Ok(case),
                Ok(_) => {}
                Err(bad) => {
                    // A key given a placeholder (its type was wrong, which
                    // is reported): what the checks say of the placeholder
                    // is no problem of the user's, also where the value came
                    // from --set (no line of the file to quiet).
                    // ": key " also matches "[section]: key ".
                    let of_placeholder = |p: &str| {
                        placeholders.iter().any(|k| {
                            [" ", ":"]
                                .iter()
                                .any(|end| p.contains(&format!(": {k}{end}")))
                        })
                    };
                    problems.extend(bad.into_iter().filter(|p| {
                        !quiet_lines.iter().any(|l| p.starts_with(l.as_str())) && !of_placeholder(p)
                    }));
                }
            }
        }
    }
    Err(InputError(listed(problems)))
}

/// [`value_spans`] of the TOML `text` (none where it does not parse).
fn spans_in(text: &str) -> BTreeMap<String, Range<usize>> {
    let mut spans = BTreeMap::new();
    if let Ok(doc) = toml_edit::Document::parse(text) {
        value_spans(doc.as_table(), "", &mut spans);
    }
    spans
}

/// The dotted key of the history (`traction.0.history`,
/// `contact.pressure_history`, ...) whose value holds `span` of `text`.
fn history_at(text: &str, span: Option<Range<usize>>) -> Option<String> {
    let at = span?.start;
    spans_in(text)
        .into_iter()
        .filter(|(k, s)| k.ends_with("history") && s.contains(&at))
        .min_by_key(|(_, s)| s.len())
        .map(|(k, _)| k)
}

/// The forms a history takes, for a message on history `key`.
fn history_forms(key: &str) -> String {
    let leaf = key.rsplit('.').next().unwrap_or(key);
    let forms = "\"constant\", \"step\", { sin = { omega = 25.13 } } (sin(omega t)) or \
                 { table = [[0.0, 0.0], [0.1, 1.0]] } (linear between [t, f] points)";
    if leaf == "history" {
        format!("; a traction's history is {forms}, e.g. history = \"step\"")
    } else {
        format!(
            "; {key} takes the forms of a traction's history: {forms}, e.g. {leaf} = \"constant\""
        )
    }
}

/// [`load_str`] on text alone, named `case.toml` in the current directory
/// (for fuzzing and property tests: any text gives a case or an error).
///
/// # Errors
/// As [`load`].
pub fn parse_str(text: &str) -> Result<Case, InputError> {
    load_str(Path::new("case.toml"), text, &[])
}

/// sin(0 t): a factor that is 0 at every t, so its load never acts.
fn zero_sine(h: &History) -> bool {
    matches!(h, History::Sin { omega } if *omega == 0.0)
}

/// A number for a message: as Rust writes it where that is short, else
/// in exponent form (`{}` wrote 1e99 with a hundred digits).
pub(crate) struct Num(pub f64);

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        if x == 0.0 || !x.is_finite() || (1e-4..1e6).contains(&x.abs()) {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}

/// Most steps a case may ask for: 1e12 steps take days even on the paper's
/// 85-node mesh (the time crate's bound on a damped critical step too).
const MAX_STEPS: f64 = stickslip_time::MAX_STABLE_STEPS;

/// Checks every value of the case serde read, collecting every problem,
/// and completes it: paths resolved against the case file's directory,
/// `output.file` defaulted, where each key is. `spans`: each value's
/// place in the text serde read, by dotted key. Every number is finite
/// and moderate here already (`keys::check_table` refused the others).
/// `reported`: dotted keys whose value was reported already and removed
/// (or replaced), which no check may call missing.
fn complete(
    mut case: Case,
    path: &Path,
    source: String,
    spans: &BTreeMap<String, Range<usize>>,
    loc: &Locator,
    reported: &[String],
) -> Result<Case, Vec<String>> {
    let mut bad = Vec::new();
    let span = |key: &str| spans.get(key).cloned();
    let mut check = |ok: bool, key: &str, msg: String| {
        if !ok {
            bad.push(format!("{}: {msg}", loc.at(span(key))));
        }
    };
    let base = path.parent().unwrap_or(Path::new("")).to_path_buf();

    // [mesh]
    let mesh_file = base.join(&case.mesh.file);
    check(
        mesh_file.is_file(),
        "mesh.file",
        if mesh_file.is_dir() {
            format!(
                "mesh.file: {} is a directory; give the .msh file in it",
                mesh_file.display()
            )
        } else if mesh_file.exists() {
            format!(
                "mesh.file: {} is not a regular file (a device, FIFO or socket); give the .msh file",
                mesh_file.display()
            )
        } else {
            format!(
                "mesh.file: {} does not exist (paths are relative to the case file's directory); \
                 check the name, or make the mesh with Gmsh",
                mesh_file.display()
            )
        },
    );

    // mesh.ladder: at least one entry. Whether its files exist is checked
    // by `advise`, which reads them; a run does not, and must not fail on them.
    if spans.contains_key("mesh.ladder") {
        check(
            !case.mesh.ladder.is_empty(),
            "mesh.ladder",
            "mesh.ladder is empty; list the meshes coarse to fine, e.g. [\"a.msh\", \"b.msh\"], or remove the key".into(),
        );
    }

    // [material]
    let m = &case.material;
    let (e, nu, rho) = (m.e, m.nu, m.rho);
    check(
        e > 0.0 && e.is_finite(),
        "material.E",
        format!(
            "material.E = {} must be a finite number > 0; give Young's modulus",
            Num(e)
        ),
    );
    check(
        rho > 0.0 && rho.is_finite(),
        "material.rho",
        format!(
            "material.rho = {} must be a finite number > 0; give the mass density",
            Num(rho)
        ),
    );
    check(
        nu > -1.0 && nu < 0.5,
        "material.nu",
        format!("material.nu = {} must lie in (-1, 0.5); 0.5 (incompressible) cannot be modelled with displacements only", Num(nu)),
    );

    if let Some(d) = &m.damping {
        for (key, value, what) in [
            ("alpha", d.alpha, "mass-proportional, 1/time"),
            ("beta", d.beta, "stiffness-proportional, time"),
        ] {
            check(
                value >= 0.0 && value.is_finite(),
                &format!("material.damping.{key}"),
                format!(
                    "material.damping.{key} = {} must be a finite number >= 0 (Rayleigh damping \
                     C = alpha M + beta K; {key} is {what}); use 0 for none",
                    Num(value)
                ),
            );
        }
    }

    // [[dirichlet]]
    for (i, d) in case.dirichlet.iter().enumerate() {
        let group = format!("dirichlet.{i}.group");
        check(
            d.ux.is_some() || d.uy.is_some(),
            &group,
            format!(
                "dirichlet.{} (group {:?}) fixes neither ux nor uy; add ux = .. and/or uy = ..",
                i, d.group
            ),
        );
    }

    // A component of a group prescribed twice: even with equal values it is
    // a copy-paste slip the user should see (different values would also
    // contradict each other).
    let mut seen: BTreeMap<(&str, usize), usize> = BTreeMap::new();
    for (i, d) in case.dirichlet.iter().enumerate() {
        for (comp, given) in [(0, d.ux.is_some()), (1, d.uy.is_some())] {
            if !given {
                continue;
            }
            if let Some(first) = seen.insert((d.group.as_str(), comp), i) {
                let c = if comp == 0 { "ux" } else { "uy" };
                check(
                    false,
                    &format!("dirichlet.{i}.group"),
                    format!(
                        "dirichlet.{} (group {:?}) sets {c} again, already set by dirichlet.{} ({}); give each component of a group once",
                        i,
                        d.group,
                        first,
                        loc.at(span(&format!("dirichlet.{first}.group")))
                    ),
                );
            }
        }
    }

    // [[traction]]
    for (i, t) in case.traction.iter().enumerate() {
        let what = format!("traction.{i} (group {:?})", t.group);
        let group = format!("traction.{i}.group");
        check(
            t.t.is_some() != t.pressure.is_some(),
            &group,
            format!(
                "{what} must give exactly one of t = [tx, ty] and pressure = p; it gives {}",
                if t.t.is_some() { "both" } else { "neither" }
            ),
        );
        let history = format!("traction.{i}.history");
        if let History::Table(p) = &t.history {
            let increasing = p.windows(2).all(|w| w[1][0] > w[0][0]);
            check(
                !p.is_empty() && increasing,
                &history,
                format!("{what}: history table needs at least one [t, f] pair and strictly increasing times; e.g. {{ table = [[0.0, 0.0], [0.1, 1.0]] }}"),
            );
        }
        check(
            !zero_sine(&t.history),
            &history,
            format!(
                "{what}: history = {{ sin = {{ omega = 0 }} }} is sin(0) = 0 at every t, so the \
                 load never acts; give the angular frequency omega (rad per unit time), use \
                 history = \"step\" or \"constant\" for a steady load, or remove the [[traction]]"
            ),
        );
    }

    // [contact]
    for (i, c) in case.contact.iter().enumerate() {
        let key = |k: &str| crate::schema::contact_key_in(spans.keys(), i, k);
        let was_reported = |k: &str| reported.contains(&key(k));
        crate::compliance::check_law(c, &key, &was_reported, &mut check);
        // A key the law lacks is refused above; 0 checks nothing here.
        let (p, mu, eps) = (c.pressure.unwrap_or(0.0), c.mu_at_rest(), c.eps);
        check(p >= 0.0 && p.is_finite(), &key("pressure"), format!("contact.pressure = {} must be >= 0 and finite (it presses the body onto the surface; g = mu * pressure)", Num(p)));
        check(
            mu >= 0.0 && mu.is_finite(),
            &key("mu"),
            format!(
                "contact.mu = {} must be >= 0 and finite; use 0 for frictionless contact",
                Num(mu)
            ),
        );
        if let Some(Mu::Speed {
            stat,
            kinetic,
            speed,
        }) = c.mu
        {
            check(
                (0.0..=stat).contains(&kinetic),
                &key("mu"),
                format!("contact.mu: kinetic = {} must be >= 0 and at most static = {} (friction falls from static to kinetic as the surface slips); give kinetic <= static, or mu = {} for one coefficient", Num(kinetic), Num(stat), Num(stat)),
            );
            check(
                speed > 0.0 && speed.is_finite(),
                &key("mu"),
                format!("contact.mu: speed = {} must be > 0 and finite (the slip speed over which mu falls from static towards kinetic, in the model's units)", Num(speed)),
            );
        }
        check(eps > 0.0 && eps.is_finite(), &key("eps"), format!("contact.eps = {} must be > 0 and finite (the friction law's regularization; the paper uses 1e-4 to 1)", Num(eps)));
        check(
            c.max_iterations > 0,
            &key("max_iterations"),
            "contact.max_iterations must be >= 1 (default 100)".into(),
        );
        if let History::Table(p) = &c.pressure_history {
            let increasing = p.windows(2).all(|w| w[1][0] > w[0][0]);
            check(
                !p.is_empty() && increasing,
                &key("pressure_history"),
                "contact.pressure_history: the table needs at least one [t, f] pair and strictly increasing times; e.g. { table = [[0.0, 1.0], [0.5, 0.2]] }".into(),
            );
        }
        if let History::Table(p) = &c.foundation_history {
            let increasing = p.windows(2).all(|w| w[1][0] > w[0][0]);
            check(
                !p.is_empty() && increasing,
                &key("foundation_history"),
                "contact.foundation_history: the table needs at least one [t, f] pair and strictly increasing times; e.g. { table = [[0.0, 0.0], [0.5, 1.0]] }".into(),
            );
        }
        // (A compliant surface refuses these histories whatever they are.)
        if c.law == ContactLaw::Pressure {
            check(
                !zero_sine(&c.pressure_history),
                &key("pressure_history"),
                "contact.pressure_history = { sin = { omega = 0 } } is 0 at every t, so the \
                 surface is never pressed and carries no friction; give the angular frequency \
                 omega (rad per unit time), or use \"constant\" (the default) for a steady pressure"
                    .into(),
            );
            check(
                !zero_sine(&c.foundation_history),
                &key("foundation_history"),
                "contact.foundation_history = { sin = { omega = 0 } } is 0 at every t, so the \
                 foundation never moves; give the angular frequency omega (rad per unit time), or \
                 remove foundation_velocity and foundation_history for a foundation at rest"
                    .into(),
            );
        }
        if let Some(profile) = &c.pressure_profile {
            let rows = &profile.table;
            let increasing = rows.windows(2).all(|w| w[1][0] > w[0][0]);
            check(
                !rows.is_empty() && increasing && rows[0][0] >= 0.0,
                &key("pressure_profile"),
                "contact.pressure_profile: the table needs at least one [s, factor] row, s >= 0 and strictly increasing along the surface (s as in /contact/s); e.g. { table = [[0.0, 1.0], [2.0, 0.5]] }".into(),
            );
            if let Some(r) = rows.iter().find(|r| !(r[1] >= 0.0 && r[1].is_finite())) {
                check(
                    false,
                    &key("pressure_profile"),
                    format!("contact.pressure_profile: factor {} at s = {} must be >= 0 and finite (a negative factor would pull the surface off; write 0 where it carries no pressure)", Num(r[1]), Num(r[0])),
                );
            }
        }
        if i > 0 {
            let first = &case.contact[0];
            check(
                c.remark_4_2 == first.remark_4_2 && c.max_iterations == first.max_iterations,
                &key("group"),
                "contact: remark_4_2 and max_iterations set the run's one stick/slip iteration; give them the same values on every [[contact]] (or on none)".into(),
            );
            if let Some(j) = case.contact[..i].iter().position(|o| o.group == c.group) {
                check(
                    false,
                    &key("group"),
                    format!("contact: group {:?} is already the group of contact.{j} (the [[contact]] entries count from 0, as --set and /contact/surface do); a node carries the friction of one surface only; give each [[contact]] its own group", c.group),
                );
            }
        }
    }

    // [time]
    let tm = &case.time;
    let (dt, t_end) = (tm.dt, tm.t_end);
    check(
        dt > 0.0 && dt.is_finite(),
        "time.dt",
        format!("time.dt = {} must be a finite number > 0", Num(dt)),
    );
    check(
        t_end > 0.0 && t_end.is_finite(),
        "time.t_end",
        format!("time.t_end = {} must be a finite number > 0", Num(t_end)),
    );
    // A run that cannot end (1e300 steps would pass `check` and run on).
    // Blamed on t_end, or on dt where only dt came from --set.
    let steps = t_end / dt;
    let by_set = |key: &str| span(key).is_some_and(|s| loc.set_by_override(&s));
    let blamed = if by_set("time.dt") && !by_set("time.t_end") {
        "time.dt"
    } else {
        "time.t_end"
    };
    check(
        steps.is_nan() || steps <= MAX_STEPS,
        blamed,
        format!(
            "time.t_end / time.dt = {t_end:e} / {dt:e} = {steps:.3e} steps, more than {MAX_STEPS:e}: \
             a run that would not end in years; check the two values (their units, a missing minus \
             sign in an exponent)"
        ),
    );
    let (beta, gamma) = (tm.beta, tm.gamma);
    if tm.scheme == Scheme::Newmark {
        // Unconditional stability of Newmark's method: 2β ≥ γ ≥ ½ (Hughes, The
        // Finite Element Method, §9.1).
        let key = ["time.gamma", "time.beta"]
            .into_iter()
            .find(|k| spans.contains_key(*k))
            .unwrap_or("time.scheme");
        check(
            gamma >= 0.5 && 2.0 * beta >= gamma,
            key,
            format!("newmark with beta = {}, gamma = {} is not unconditionally stable (needs 2*beta >= gamma >= 0.5); use e.g. beta = 0.25, gamma = 0.5 (trapezoidal) or beta = 0.3025, gamma = 0.6 (damped)", Num(beta), Num(gamma)),
        );
    }
    if tm.scheme != Scheme::Newmark {
        // Newmark's parameters on another scheme would be ignored
        // silently: say so (a Newmark case switched by --set keeps them).
        for key in ["beta", "gamma"] {
            let dotted = format!("time.{key}");
            if spans.contains_key(&dotted) {
                check(
                    false,
                    &dotted,
                    format!(
                        "time.{key} is a Newmark parameter; scheme = \"{}\" has none: \
                         remove it, or use scheme = \"newmark\"",
                        tm.scheme.name()
                    ),
                );
            }
        }
    }
    if let (Scheme::CentralDifference, Some(m)) = (tm.scheme, tm.mass) {
        check(
            m == MassKind::Lumped,
            "time.mass",
            "central_difference needs mass = \"lumped\" (with a consistent mass it is no longer explicit); remove the key or use scheme = \"newmark\"".into(),
        );
    }
    if tm.scheme != Scheme::CentralDifference && tm.allow_unstable {
        // As beta on central difference: a key the scheme would ignore.
        check(
            false,
            "time.allow_unstable",
            format!(
                "time.allow_unstable lets central difference run above its critical step; \
                 scheme = \"{}\" has no critical step: remove it, or use scheme = \"central_difference\"",
                tm.scheme.name()
            ),
        );
    }
    if tm.scheme == Scheme::QuasiStatic {
        // Keys of inertia would be ignored silently by increments without
        // it: refuse each at its line.
        let init = &case.initial;
        let inertia = [
            (tm.mass.is_some(), "time.mass", "no mass: remove time.mass"),
            (
                case.material.damping.is_some(),
                "material.damping",
                "no damping: remove material.damping",
            ),
            (
                init.velocity.is_some(),
                "initial.velocity",
                "no initial velocity: remove initial.velocity",
            ),
            (
                !init.velocities.is_empty(),
                "initial.velocities.0.group",
                "no initial velocity: remove [[initial.velocities]]",
            ),
            // The increments ran with it and failed at the first reduced
            // one, advising what does not help.
            (
                tm.stick_reduction.is_some(),
                "time.stick_reduction",
                "no step reduction after sticking (Remark 4.3 is a cure for the dynamic \
                 schemes): remove time.stick_reduction",
            ),
        ];
        for (given, key, what) in inertia {
            check(
                !given,
                key,
                format!("quasi_static increments have no inertia, so {what}"),
            );
        }
    }
    if let Some(r) = &tm.stick_reduction {
        check(
            r.dt > 0.0 && r.dt <= dt,
            "time.stick_reduction.dt",
            format!(
                "time.stick_reduction.dt = {} must be > 0 and <= time.dt = {}",
                Num(r.dt),
                Num(dt)
            ),
        );
        // A reduced step whose velocity update divides differences at
        // round-off (REDUCTION_MIN_RATIO).
        check(
            // (1e-12 for Δt = 1e-3 is allowed, whatever 1e-9 · 1e-3 rounds to.)
            !(r.dt > 0.0 && r.dt < REDUCTION_MIN_RATIO * dt * (1.0 - 1e-9)),
            "time.stick_reduction.dt",
            format!(
                "time.stick_reduction.dt = {} is below {REDUCTION_MIN_RATIO:e} x time.dt = {}: \
                 steps that short compute velocities from differences at round-off; use at \
                 least {:.1e} (the paper's reduced steps are 1e-4 of its Δt)",
                Num(r.dt),
                Num(dt),
                REDUCTION_MIN_RATIO * dt
            ),
        );
        check(
            r.steps > 0,
            "time.stick_reduction.steps",
            "time.stick_reduction.steps must be >= 1; remove stick_reduction to turn the reduction off".into(),
        );
    }

    // [output]
    let o = &case.output;
    check(
        o.every != Some(0),
        "output.every",
        "output.every must be >= 1 (1 writes the fields at every step)".into(),
    );
    check(
        o.frames != Some(0),
        "output.frames",
        "output.frames must be >= 1 (frames of the fields over [0, t_end]; default 200)".into(),
    );
    if let Some(dt) = o.interval {
        check(
            dt > 0.0,
            "output.interval",
            format!(
                "output.interval = {} must be > 0 (the simulated time between frames)",
                Num(dt)
            ),
        );
    }
    // One rule for when the fields are written: a second one is refused
    // where it stands (the later in the text), rather than one of them
    // silently ignored.
    let mut given: Vec<(usize, &str)> = ["frames", "interval", "every"]
        .into_iter()
        .filter_map(|k| Some((spans.get(&format!("output.{k}"))?.start, k)))
        .collect();
    given.sort_unstable();
    let given: Vec<&str> = given.into_iter().map(|(_, k)| k).collect();
    if let [first, rest @ ..] = &given[..] {
        for other in rest {
            check(
                false,
                &format!("output.{other}"),
                format!(
                    "output.{other} and output.{first} both say when the fields are written; \
                     keep one of them (frames: N over [0, t_end], interval: simulated time \
                     between frames, every: N steps)"
                ),
            );
        }
    }
    if let Some(n) = o.flush_every {
        check(
            n > 0,
            "output.flush_every",
            "output.flush_every must be >= 1 (steps between flushes of the results file; \
             default: none, by output.flush_seconds only)"
                .into(),
        );
    }
    check(
        o.flush_seconds > 0.0 && !o.flush_seconds.is_nan(),
        "output.flush_seconds",
        format!(
            "output.flush_seconds = {} must be > 0 (seconds between flushes; default 5)",
            Num(o.flush_seconds)
        ),
    );
    if let Some(c) = o.compression {
        check(
            c <= 9,
            "output.compression",
            format!("output.compression = {c} must be 0 (none) to 9 (deflate level; default 0)"),
        );
    }

    if !bad.is_empty() {
        return Err(bad);
    }
    case.output.file = if spans.contains_key("output.file") {
        base.join(&case.output.file)
    } else {
        let stem = path
            .file_stem()
            .map_or("results".into(), |s| s.to_string_lossy().into_owned());
        base.join(format!("{stem}.h5"))
    };
    case.mesh.file = mesh_file;
    case.mesh.ladder_text = case
        .mesh
        .ladder
        .iter()
        .map(|f| f.display().to_string())
        .collect();
    case.mesh.ladder = case.mesh.ladder.iter().map(|f| base.join(f)).collect();
    case.path = path.to_path_buf();
    case.source = source;
    case.locations = spans
        .iter()
        .map(|(k, s)| (k.clone(), loc.at(Some(s.clone()))))
        .collect();
    Ok(case)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    use crate::{restart_changes, DirichletSection, Hypothesis, MaterialSection};

    /// A directory with a mesh file placeholder, so mesh.file exists.
    fn scratch(name: &str) -> PathBuf {
        let d = stickslip_testkit::scratch(&format!("case-{name}"));
        std::fs::write(d.join("m.msh"), "").unwrap();
        d
    }

    const GOOD: &str = r#"title = "slab"
[mesh]
file = "m.msh"
[material]
E = 1000
nu = 0.3
rho = 1.0
[[dirichlet]]
group = "support"
uy = 0.0
[[dirichlet]]
group = "left"
ux = 0.0
[[traction]]
group = "load"
t = [-150.0, 0.0]   # compressive
[contact]
group = "contact"
pressure = 300.0
mu = 0.3
eps = 1e-4
[time]
scheme = "central_difference"
dt = 1e-3
t_end = 0.5
"#;

    fn load_text(name: &str, text: &str, sets: &[&str]) -> Result<Case, InputError> {
        let d = scratch(name);
        let p = d.join("case.toml");
        std::fs::write(&p, text).unwrap();
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        load(&p, &sets)
    }

    /// The 1-based line of the first line of `text` containing `needle`:
    /// expected locations come from the test's own text, not the code.
    fn line_of(text: &str, needle: &str) -> usize {
        text.lines()
            .position(|l| l.contains(needle))
            .expect("needle in text")
            + 1
    }

    #[test]
    fn mesh_ladder_is_read_resolved_and_checked() {
        let text = GOOD.replace(
            "file = \"m.msh\"",
            "file = \"m.msh\"\nladder = [\"m.msh\", \"m.msh\"]  # coarse to fine",
        );
        let c = load_text("ladder", &text, &[]).unwrap();
        let dir = c.path.parent().unwrap().to_path_buf();
        assert_eq!(c.mesh.ladder, vec![dir.join("m.msh"), dir.join("m.msh")]);
        assert_eq!(c.mesh.ladder_text, vec!["m.msh", "m.msh"]);
        assert!(load_text("ladder-none", GOOD, &[])
            .unwrap()
            .mesh
            .ladder
            .is_empty());
        // A missing file does not stop a run (advise checks the files); an
        // empty list and a wrong type are refused, named at their line.
        let missing = text.replace("[\"m.msh\", \"m.msh\"]", "[\"m.msh\", \"nope.msh\"]");
        assert!(load_text("ladder-missing", &missing, &[]).is_ok());
        let line = line_of(&missing, "ladder");
        let empty = text.replace("[\"m.msh\", \"m.msh\"]", "[]");
        let e = load_text("ladder-empty", &empty, &[]).unwrap_err().0;
        assert!(e.contains("mesh.ladder is empty"), "{e}");
        let wrong = text.replace("[\"m.msh\", \"m.msh\"]", "\"m.msh\"");
        let e = load_text("ladder-type", &wrong, &[]).unwrap_err().0;
        assert!(
            e.contains("mesh.ladder: expected a list of mesh files"),
            "{e}"
        );
        assert!(e.contains(&format!("case.toml:{line}:")), "{e}");
        // A typo is caught by the unknown-key machinery with a suggestion.
        let typo = text.replace("ladder =", "ladders =");
        let e = load_text("ladder-typo", &typo, &[]).unwrap_err().0;
        assert!(e.contains("did you mean `ladder`?"), "{e}");
        // A restart may add or change the ladder: advise reads it, a run does not.
        assert!(restart_changes(GOOD, &text).unwrap().is_empty());
    }

    #[test]
    fn good_case_and_defaults() {
        let c = load_text("good", GOOD, &[]).unwrap();
        let dir = c.path.parent().unwrap().to_path_buf();
        assert_eq!(c.title.as_deref(), Some("slab"));
        assert_eq!(c.mesh.file, dir.join("m.msh"));
        assert_eq!(
            c.material,
            MaterialSection {
                e: 1000.0,
                nu: 0.3,
                rho: 1.0,
                hypothesis: Hypothesis::PlaneStrain,
                damping: None,
            }
        );
        assert_eq!(c.dirichlet.len(), 2);
        assert_eq!(
            c.dirichlet[1],
            DirichletSection {
                group: "left".into(),
                ux: Some(0.0),
                uy: None
            }
        );
        assert_eq!(c.traction[0].t, Some([-150.0, 0.0]));
        assert_eq!(
            c.traction[0].history,
            History::Step,
            "DESIGN.md: history defaults to step"
        );
        let k = &c.contact[0];
        assert!(k.remark_4_2);
        assert_eq!(k.max_iterations, 100);
        assert_eq!(c.time.scheme, Scheme::CentralDifference);
        assert_eq!((c.time.beta, c.time.gamma), (0.25, 0.5));
        assert_eq!(c.time.mass, None);
        assert!(!c.time.allow_unstable);
        assert_eq!(
            c.output.file,
            dir.join("case.h5"),
            "default output is <case stem>.h5 beside the case"
        );
        assert_eq!(c.output.every, None);
        assert_eq!(
            c.output.fields(),
            crate::schema::Fields::Frames(crate::schema::DEFAULT_FRAMES),
            "the fields at frames by default"
        );
        assert_eq!(c.source, GOOD);
    }

    #[test]
    fn unknown_key_names_file_line_and_key() {
        let text = GOOD.replace("eps = 1e-4", "eps = 1e-4\nepsilon = 2");
        let e = load_text("unknown", &text, &[]).unwrap_err().0;
        let l = line_of(&text, "epsilon");
        assert!(
            e.contains(&format!("case.toml:{l}:1: unknown field `epsilon`")),
            "{e}"
        );
    }

    /// A key in the wrong table is sent to the table the schema has it in,
    /// a list of tables and a nested table included.
    #[test]
    fn misplaced_keys_name_their_table() {
        let text = GOOD.replace("t_end = 0.5", "t_end = 0.5\nsteps = 3\nux = 0.0");
        let e = load_text("misplaced", &text, &[]).unwrap_err().0;
        assert!(
            e.contains("`steps` belongs in [time.stick_reduction]; move it there"),
            "{e}"
        );
        assert!(
            e.contains("`ux` belongs in [[dirichlet]]; move it there"),
            "{e}"
        );
    }

    #[test]
    fn syntax_error_has_line() {
        let text = GOOD.replace("mu = 0.3", "mu = = 0.3");
        let e = load_text("syntax", &text, &[]).unwrap_err().0;
        let l = line_of(&text, "mu = =");
        assert!(
            e.contains(&format!("case.toml:{l}:")) && e.contains("invalid TOML"),
            "{e}"
        );
    }

    #[test]
    fn all_value_problems_are_reported_together() {
        let text = GOOD
            .replace("E = 1000", "E = -1")
            .replace("nu = 0.3", "nu = 0.5")
            .replace("rho = 1.0", "rho = 0")
            .replace("mu = 0.3", "mu = -0.1")
            .replace("eps = 1e-4", "eps = 0.0")
            .replace("dt = 1e-3", "dt = -1e-3")
            .replace(
                "t_end = 0.5",
                "t_end = 0\nmass = \"consistent\"\nstick_reduction = { dt = 1e-2, steps = 3 }",
            )
            .replace("file = \"m.msh\"", "file = \"missing.msh\"")
            .replace("uy = 0.0", "")
            .replace(
                "t = [-150.0, 0.0]   # compressive",
                "t = [-150.0, 0.0]\npressure = 2.0",
            )
            + "[output]\nevery = 0\n";
        let e = load_text("many", &text, &[]).unwrap_err().0;
        let expect = [
            ("E = -1", "material.E"),
            ("nu = 0.5", "material.nu"),
            ("rho = 0", "material.rho"),
            ("mu = -0.1", "contact.mu"),
            ("eps = 0.0", "contact.eps"),
            ("dt = -1e-3", "time.dt"),
            ("t_end = 0", "time.t_end"),
            ("mass = ", "central_difference needs mass = \"lumped\""),
            ("stick_reduction", "time.stick_reduction.dt"),
            ("missing.msh", "does not exist"),
            ("group = \"support\"", "fixes neither ux nor uy"),
            ("group = \"load\"", "exactly one of t"),
            ("every = 0", "output.every"),
        ];
        for (needle, what) in expect {
            let l = line_of(&text, needle);
            assert!(
                e.lines()
                    .any(|m| m.contains(&format!("case.toml:{l}:")) && m.contains(what)),
                "no '{what}' at line {l} in:\n{e}"
            );
        }
        assert_eq!(
            e.lines().count(),
            expect.len(),
            "one line per problem:\n{e}"
        );
    }

    #[test]
    fn one_rule_for_the_frames() {
        for (keys, fields) in [
            ("frames = 7\n", crate::schema::Fields::Frames(7)),
            ("interval = 0.25\n", crate::schema::Fields::Interval(0.25)),
            ("every = 3\n", crate::schema::Fields::Every(3)),
        ] {
            let c = load_text("frames", &format!("{GOOD}[output]\n{keys}"), &[]).unwrap();
            assert_eq!(c.output.fields(), fields, "{keys}");
        }
        // Two rules: the second is refused at its line, the first named.
        let text = format!("{GOOD}[output]\nframes = 7\nevery = 3\ninterval = 0.0\n");
        let e = load_text("two", &text, &[]).unwrap_err().0;
        for (needle, what) in [
            ("every = 3", "output.every and output.frames both say"),
            (
                "interval = 0.0",
                "output.interval and output.frames both say",
            ),
            ("interval = 0.0", "output.interval = 0 must be > 0"),
        ] {
            let l = line_of(&text, needle);
            assert!(
                e.lines()
                    .any(|m| m.contains(&format!("case.toml:{l}:")) && m.contains(what)),
                "no '{what}' at line {l} in:\n{e}"
            );
        }
        // A --set of another rule than the file's replaces it.
        let c = load_text(
            "set-rule",
            &format!("{GOOD}[output]\nevery = 1\n"),
            &["output.frames=10"],
        )
        .unwrap();
        assert_eq!(c.output.fields(), crate::schema::Fields::Frames(10));
        assert_eq!(c.output.every, None);
        assert!(!c.source.contains("every"), "{}", c.source);
        let e = load_text("zero", &format!("{GOOD}[output]\nframes = 0\n"), &[])
            .unwrap_err()
            .0;
        assert!(e.contains("output.frames must be >= 1"), "{e}");
    }

    #[test]
    fn the_later_of_two_frame_rules_is_refused_at_its_line() {
        // `every` before `frames` in the file: the message goes to the
        // line of `frames`, the one that comes second, naming `every`.
        let text = format!("{GOOD}[output]\nevery = 3\nframes = 7\n");
        let e = load_text("two-later", &text, &[]).unwrap_err().0;
        let l = line_of(&text, "frames = 7");
        assert!(
            e.lines().any(|m| m.contains(&format!("case.toml:{l}:"))
                && m.contains("output.frames and output.every both say")),
            "not at line {l}:\n{e}"
        );
        assert_eq!(e.lines().count(), 1, "{e}");
    }

    #[test]
    fn a_negative_count_is_refused_with_its_minimum() {
        // The counts start at 1; compression, a level, at 0.
        for (key, min) in [
            ("frames", 1),
            ("every", 1),
            ("flush_every", 1),
            ("compression", 0),
        ] {
            let text = format!("{GOOD}[output]\n{key} = -5\n");
            let e = load_text(&format!("neg-{key}"), &text, &[]).unwrap_err().0;
            assert!(
                e.contains(&format!(
                    "output.{key}: expected a whole number >= {min}, found the integer -5"
                )),
                "{e}"
            );
        }
        let text = GOOD.replace("eps = 1e-4", "eps = 1e-4\nmax_iterations = -1");
        let e = load_text("neg-iterations", &text, &[]).unwrap_err().0;
        assert!(
            e.contains("contact.max_iterations: expected a whole number >= 1"),
            "{e}"
        );
        let text = GOOD.replace(
            "t_end = 0.5",
            "t_end = 0.5\nstick_reduction = { dt = 1e-4, steps = -2 }",
        );
        let e = load_text("neg-steps", &text, &[]).unwrap_err().0;
        assert!(
            e.contains("time.stick_reduction.steps: expected a whole number >= 1"),
            "{e}"
        );
    }

    #[test]
    fn newmark_stability_condition() {
        // 2β ≥ γ ≥ ½ (textbook unconditional stability): (0.3025, 0.6) passes,
        // (0.25, 0.4) and (0.2, 0.5) fail.
        let nm = GOOD.replace("\"central_difference\"", "\"newmark\"");
        let ok = load_text("nm-ok", &nm, &["time.beta=0.3025", "time.gamma=0.6"]).unwrap();
        assert_eq!((ok.time.beta, ok.time.gamma), (0.3025, 0.6));
        for (b, g) in [(0.25, 0.4), (0.2, 0.5)] {
            let text = nm.replace("dt = 1e-3", &format!("dt = 1e-3\nbeta = {b}\ngamma = {g}"));
            let e = load_text("nm-bad", &text, &[]).unwrap_err().0;
            assert!(e.contains("not unconditionally stable"), "{e}");
            assert!(
                e.contains(&format!("case.toml:{}:", line_of(&text, "gamma ="))),
                "{e}"
            );
        }
    }

    #[test]
    fn quasi_static_refuses_the_keys_of_inertia_at_their_lines() {
        // Damping and initial velocities mean nothing without inertia;
        // quasi-static increments would ignore them silently.
        let text = GOOD
            .replace("\"central_difference\"", "\"quasi_static\"")
            .replace("rho = 1.0", "rho = 1.0\ndamping = { alpha = 1.0, beta = 0.0 }")
            + "[initial]\nvelocity = [1.0, 0.0]\n[[initial.velocities]]\ngroup = \"load\"\nvelocity = [0.0, 1.0]\n";
        let e = load_text("qs-inertia", &text, &[]).unwrap_err().0;
        for (needle, what) in [
            ("damping =", "no damping"),
            ("velocity = [1.0", "no initial velocity"),
            ("group = \"load\"\nvelocity", "no initial velocity"),
        ] {
            let line = match needle.split_once('\n') {
                // The entry's group line, which follows the table header.
                Some((first, _)) => text
                    .lines()
                    .enumerate()
                    .filter(|(_, l)| l.contains(first))
                    .map(|(i, _)| i + 1)
                    .last()
                    .expect("the entry's group"),
                None => line_of(&text, needle),
            };
            assert!(e.contains(&format!("case.toml:{line}:")), "{needle}: {e}");
            assert!(e.contains(what), "{what}: {e}");
        }
    }

    #[test]
    fn table_rows_cd_parameters_and_an_empty_file_are_reported_where_they_are() {
        let with = |rows: &str| {
            GOOD.replace(
                "t = [-150.0, 0.0]   # compressive",
                &format!("t = [-150.0, 0.0]\nhistory = {{ table = {rows} }}"),
            )
        };
        assert!(load_text("rows-ok", &with("[[0.0, 0.0], [0.1, 1.0]]"), &[]).is_ok());
        // serde's [f64; 2] took a third number and dropped it.
        let text = with("[[0.0, 0.0], [0.1, 1.0, 99.0]]");
        let e = load_text("rows-3", &text, &[]).unwrap_err().0;
        assert!(e.contains("table row 2 has 3 numbers"), "{e}");
        assert!(
            e.contains(&format!("case.toml:{}:", line_of(&text, "history ="))),
            "{e}"
        );
        // Newmark's parameters on a central-difference run were ignored.
        let text = GOOD.replace("dt = 1e-3", "dt = 1e-3\nbeta = 0.3");
        let e = load_text("cd-beta", &text, &[]).unwrap_err().0;
        assert!(e.contains("time.beta is a Newmark parameter"), "{e}");
        assert!(
            e.contains(&format!("case.toml:{}:", line_of(&text, "beta ="))),
            "{e}"
        );
        // No --set to blame in an empty file.
        let e = load_text("empty", "", &[]).unwrap_err().0;
        assert!(e.contains("case.toml: missing field `mesh`"), "{e}");
        assert!(!e.contains("--set"), "{e}");
    }

    #[test]
    fn set_replaces_inserts_and_keeps_lines() {
        let c = load_text(
            "set",
            GOOD,
            &[
                "time.dt=5e-4",
                "time.scheme=newmark",
                "contact.remark_4_2=false",
                "dirichlet.0.uy=0.5",
                "output.every=10",
            ],
        )
        .unwrap();
        assert_eq!(c.time.dt, 5e-4);
        assert_eq!(c.time.scheme, Scheme::Newmark);
        assert!(!c.contact[0].remark_4_2);
        assert_eq!(c.dirichlet[0].uy, Some(0.5));
        assert_eq!(c.output.fields(), crate::schema::Fields::Every(10));
        // The source is the case as run, and still carries the user's comment.
        let again = load_str(&c.path, &c.source, &[]).unwrap();
        assert_eq!(again.time, c.time);
        assert!(c.source.contains("# compressive"));
        // A problem on a line --set did not touch keeps its original line even
        // though --set inserted a line before it.
        let text = GOOD.replace("t_end = 0.5", "t_end = -0.5");
        let e = load_text("set-shift", &text, &["contact.remark_4_2=false"])
            .unwrap_err()
            .0;
        assert!(
            e.contains(&format!("case.toml:{}:", line_of(&text, "t_end"))),
            "{e}"
        );
    }

    /// Too many steps is blamed on the value that came from --set: a tiny
    /// dt given by --set named t_end's line of the file.
    #[test]
    fn endless_runs_blame_the_set_value() {
        let e = load_text("set-dt", GOOD, &["time.dt=1e-14"]).unwrap_err().0;
        assert!(
            e.contains("--set time.dt=1e-14") && e.contains("more than 1e12"),
            "{e}"
        );
        let e = load_text("set-t-end", GOOD, &["time.t_end=1e20"])
            .unwrap_err()
            .0;
        assert!(
            e.contains("--set time.t_end=1e20") && e.contains("more than 1e12"),
            "{e}"
        );
        // Neither set: t_end's line of the file.
        let text = GOOD.replace("t_end = 0.5", "t_end = 1e20");
        let e = load_text("file-t-end", &text, &[]).unwrap_err().0;
        assert!(
            e.contains(&format!("case.toml:{}:", line_of(&text, "t_end"))),
            "{e}"
        );
    }

    #[test]
    fn set_problems_name_the_set() {
        let e = load_text("set-bad", GOOD, &["contact.eps=0"])
            .unwrap_err()
            .0;
        assert!(
            e.contains("--set contact.eps=0") && e.contains("contact.eps = 0 must be > 0"),
            "{e}"
        );
        let e = load_text("set-typo", GOOD, &["time.dtt=1"]).unwrap_err().0;
        assert!(
            e.contains("--set time.dtt=1") && e.contains("unknown field `dtt`"),
            "{e}"
        );
        let e = load_text("set-idx", GOOD, &["dirichlet.5.uy=0"])
            .unwrap_err()
            .0;
        assert!(e.contains("dirichlet has 2 entries"), "{e}");
        let e = load_text("set-noeq", GOOD, &["time.dt"]).unwrap_err().0;
        assert!(e.contains("expected KEY=VALUE"), "{e}");
    }

    #[test]
    fn history_forms_and_values() {
        let text = GOOD.replace(
            "t = [-150.0, 0.0]   # compressive",
            "t = [-150.0, 0.0]\nhistory = { table = [[0.0, 0.0], [0.1, 1.0], [0.3, 0.0]] }",
        );
        let h = load_text("hist", &text, &[]).unwrap().traction[0]
            .history
            .clone();
        // Piecewise linear through the given points, constant beyond the ends.
        for (t, f) in [
            (-1.0, 0.0),
            (0.0, 0.0),
            (0.05, 0.5),
            (0.1, 1.0),
            (0.2, 0.5),
            (0.3, 0.0),
            (9.0, 0.0),
        ] {
            assert!(
                (h.value(t) - f).abs() < 1e-15,
                "table({t}) = {} != {f}",
                h.value(t)
            );
        }
        let c = load_text(
            "hist-sin",
            GOOD,
            &["traction.0.history={ sin = { omega = 25.132741 } }"],
        )
        .unwrap();
        let h = &c.traction[0].history;
        assert_eq!(*h, History::Sin { omega: 25.132741 });
        assert!((h.value(1.0 / 16.0) - (25.132741f64 / 16.0).sin()).abs() < 1e-15);
        // H(t): H(0) = 1 (load on at t = 0), off before; constant is always on.
        assert_eq!(
            (History::Step.value(0.0), History::Step.value(-1e-12)),
            (1.0, 0.0)
        );
        assert_eq!(History::Constant.value(-1.0), 1.0);
        let bad = GOOD.replace(
            "t = [-150.0, 0.0]   # compressive",
            "t = [-150.0, 0.0]\nhistory = { table = [[0.2, 0.0], [0.1, 1.0]] }",
        );
        let e = load_text("hist-bad", &bad, &[]).unwrap_err().0;
        assert!(
            e.contains("strictly increasing")
                && e.contains(&format!("case.toml:{}:", line_of(&bad, "history"))),
            "{e}"
        );
        let e = load_text("hist-ramp", GOOD, &["traction.0.history=ramp"])
            .unwrap_err()
            .0;
        assert!(e.contains("unknown variant `ramp`"), "{e}");
    }

    /// Remark 4.3's step reduction is a cure for the dynamics: quasi-static
    /// increments ran with it and failed at the first reduced one, advising
    /// "raise contact.max_iterations, or reduce time.dt", neither of which
    /// helped. Refused at its line, as the other keys of inertia.
    #[test]
    fn quasi_static_refuses_stick_reduction_at_its_line() {
        let text = GOOD
            .replace("\"central_difference\"", "\"quasi_static\"")
            .replace(
                "t_end = 0.5",
                "t_end = 0.5\nstick_reduction = { dt = 1e-5, steps = 10 }",
            );
        let e = load_text("qs-reduction", &text, &[]).unwrap_err().0;
        let l = line_of(&text, "stick_reduction");
        assert!(
            e.lines().any(|m| m.contains(&format!("case.toml:{l}:"))
                && m.contains("quasi_static increments have no inertia")
                && m.contains("remove time.stick_reduction")),
            "{e}"
        );
        assert_eq!(e.lines().count(), 1, "{e}");
        // Through --set too; the dynamic schemes keep it.
        let e = load_text(
            "qs-reduction-set",
            GOOD,
            &[
                "time.scheme=quasi_static",
                "time.stick_reduction={dt=1e-5,steps=10}",
            ],
        )
        .unwrap_err()
        .0;
        assert!(e.contains("--set time.stick_reduction="), "{e}");
        for scheme in ["central_difference", "newmark"] {
            let c = load_text(
                "reduction-dynamic",
                GOOD,
                &[
                    &format!("time.scheme={scheme}"),
                    "time.stick_reduction={dt=1e-5,steps=10}",
                ],
            );
            assert!(c.is_ok(), "{scheme}: {c:?}");
        }
    }

    /// A run stopped by contact.max_iterations says to raise it, and the
    /// restart that does was refused as a change of "what the stored run
    /// computed". The budget may change; the restarted case carries the
    /// new one into the run's settings.
    #[test]
    fn a_restart_may_change_the_iteration_budget() {
        let stored = load_text("maxit-stored", GOOD, &["contact.max_iterations=2"]).unwrap();
        let raised = load_text("maxit-raised", GOOD, &["contact.max_iterations=1000"]).unwrap();
        assert_eq!(
            restart_changes(&stored.source, &raised.source).unwrap(),
            Vec::<String>::new()
        );
        assert_eq!(crate::settings(&raised).iteration.max_iterations, 1000);
        // Given in one and left to its default in the other; in a list of
        // [[contact]] tables.
        assert!(restart_changes(GOOD, &raised.source).unwrap().is_empty());
        let listed = GOOD.replace("[contact]", "[[contact]]");
        let more = listed.replace("eps = 1e-4", "eps = 1e-4\nmax_iterations = 500");
        assert!(restart_changes(&listed, &more).unwrap().is_empty());
        // The physics next to it still may not change.
        let changed = more.replace("mu = 0.3", "mu = 0.2");
        assert_eq!(
            restart_changes(&listed, &changed).unwrap(),
            vec!["contact.0.mu: 0.3 in the stored run, 0.2 now".to_string()]
        );
        let other = GOOD.replace("eps = 1e-4", "eps = 1e-4\nremark_4_2 = false");
        assert_eq!(restart_changes(GOOD, &other).unwrap().len(), 1);
    }

    /// A stored run of an earlier version that gave a key which did nothing
    /// under its scheme, and which this version refuses there, restarts
    /// from its case with the key dropped; where the key acts it may not
    /// change.
    #[test]
    fn a_restart_drops_keys_its_scheme_never_read() {
        let with =
            |scheme: &str, key: &str| format!("[time]\nscheme = \"{scheme}\"\n{key}\ndt = 1e-3\n");
        let bare = |scheme: &str| with(scheme, "");
        let inert = [
            ("newmark", "allow_unstable = true"),
            ("quasi_static", "allow_unstable = true"),
            ("quasi_static", "stick_reduction = { dt = 1e-7, steps = 3 }"),
        ];
        for (scheme, key) in inert {
            let changes = restart_changes(&with(scheme, key), &bare(scheme)).unwrap();
            assert!(changes.is_empty(), "{scheme}, {key}: {changes:?}");
        }
        let acting = [
            ("central_difference", "allow_unstable = true"),
            ("newmark", "stick_reduction = { dt = 1e-7, steps = 3 }"),
        ];
        for (scheme, key) in acting {
            let changes = restart_changes(&with(scheme, key), &bare(scheme)).unwrap();
            assert!(!changes.is_empty(), "{scheme}, {key}: {changes:?}");
        }
    }

    /// Serde's words for a history of the wrong form ("invalid type: unit
    /// variant, expected struct variant; use one of the values listed",
    /// with none listed; "History::Sin") are replaced by what is wrong and
    /// the forms a history takes, at the history's line.
    #[test]
    fn a_history_of_the_wrong_form_is_named_with_the_forms() {
        let with = |h: &str| {
            GOOD.replace(
                "t = [-150.0, 0.0]   # compressive",
                &format!("t = [-150.0, 0.0]\nhistory = {h}"),
            )
        };
        for (h, what) in [
            ("\"sin\"", "\"sin\" alone lacks the angular frequency"),
            ("\"table\"", "\"table\" alone lacks the points"),
            (
                "{ sin = 25.0 }",
                "found the number 25: write { sin = { omega = 25 } }",
            ),
            ("{ sin = { w = 1 } }", "sin has no key `w`"),
            ("{ table = 3 }", "table takes a list of [t, f] points"),
            ("{ step = 1 }", "step is written as text"),
            (
                "1",
                "a history is text or a table of one key, found the number 1",
            ),
        ] {
            let text = with(h);
            let e = load_text("hist-form", &text, &[]).unwrap_err().0;
            let l = line_of(&text, "history =");
            assert!(
                e.contains(&format!("case.toml:{l}:"))
                    && e.contains(what)
                    && e.contains("a traction's history is \"constant\", \"step\", { sin = { omega = 25.13 } }")
                    && e.contains("{ table = [[0.0, 0.0], [0.1, 1.0]] }"),
                "{h}: {e}"
            );
            for jargon in ["variant, expected", "History::", "values listed"] {
                assert!(!e.contains(jargon), "{h}: {e}");
            }
            assert_eq!(e.lines().count(), 1, "{h}: {e}");
        }
        // The contact's histories are named as themselves.
        for key in ["pressure_history", "foundation_history"] {
            let text = GOOD.replace("eps = 1e-4", &format!("eps = 1e-4\n{key} = \"sin\""));
            let e = load_text("hist-contact", &text, &[]).unwrap_err().0;
            assert!(
                e.contains(&format!("case.toml:{}:", line_of(&text, key)))
                    && e.contains(&format!(
                        "contact.{key} takes the forms of a traction's history"
                    )),
                "{key}: {e}"
            );
        }
        // The good forms still read.
        for (h, want) in [
            ("\"constant\"", History::Constant),
            ("{ sin = { omega = 2 } }", History::Sin { omega: 2.0 }),
            (
                "{ table = [[0, 0], [1.0, 2]] }",
                History::Table(vec![[0.0, 0.0], [1.0, 2.0]]),
            ),
        ] {
            let c = load_text("hist-good", &with(h), &[]).unwrap();
            assert_eq!(c.traction[0].history, want, "{h}");
        }
    }

    /// A sine of omega = 0 is 0 at every t: the load it scales never acts.
    #[test]
    fn a_sine_of_zero_frequency_is_refused() {
        let e = load_text(
            "sin0",
            GOOD,
            &["traction.0.history={ sin = { omega = 0 } }"],
        )
        .unwrap_err()
        .0;
        assert!(
            e.contains("is sin(0) = 0 at every t, so the load never acts"),
            "{e}"
        );
        for (key, what) in [
            ("pressure_history", "never pressed"),
            ("foundation_history", "never moves"),
        ] {
            let text = GOOD.replace(
                "eps = 1e-4",
                &format!("eps = 1e-4\n{key} = {{ sin = {{ omega = 0.0 }} }}"),
            );
            let e = load_text("sin0-contact", &text, &[]).unwrap_err().0;
            assert!(
                e.contains(&format!("case.toml:{}:", line_of(&text, key))) && e.contains(what),
                "{key}: {e}"
            );
        }
        assert!(load_text(
            "sin1",
            GOOD,
            &["traction.0.history={ sin = { omega = -3 } }"]
        )
        .is_ok());
    }

    /// `allow_unstable` lets central difference run above its critical
    /// step; the other schemes have none, and ignored it silently (while
    /// `beta` on central difference is refused).
    #[test]
    fn allow_unstable_is_refused_where_there_is_no_critical_step() {
        for scheme in ["newmark", "quasi_static"] {
            let text = GOOD
                .replace("\"central_difference\"", &format!("\"{scheme}\""))
                .replace("t_end = 0.5", "t_end = 0.5\nallow_unstable = true");
            let e = load_text("unstable", &text, &[]).unwrap_err().0;
            let l = line_of(&text, "allow_unstable");
            assert!(
                e.contains(&format!("case.toml:{l}:"))
                    && e.contains(&format!("scheme = \"{scheme}\" has no critical step")),
                "{scheme}: {e}"
            );
            assert_eq!(e.lines().count(), 1, "{scheme}: {e}");
            // false, the default, asks for nothing the scheme lacks.
            let off = text.replace("allow_unstable = true", "allow_unstable = false");
            assert!(load_text("stable", &off, &[]).is_ok(), "{scheme}");
        }
        let c = load_text("cd-unstable", GOOD, &["time.allow_unstable=true"]).unwrap();
        assert!(c.time.allow_unstable);
    }

    /// One rule for the fields on the command line: a file's rule is
    /// replaced by a --set of another, but two different rules set in one
    /// command contradict each other as in a file (the last one won).
    #[test]
    fn two_frame_rules_set_on_one_command_line_are_refused() {
        let e = load_text("two-sets", GOOD, &["output.frames=10", "output.every=5"])
            .unwrap_err()
            .0;
        assert!(
            e.contains("--set output.every=5: output.every and output.frames (--set output.frames=10) both say"),
            "{e}"
        );
        // The same rule twice: the last value, as for any key.
        let c = load_text("same-rule", GOOD, &["output.every=10", "output.every=5"]).unwrap();
        assert_eq!(c.output.fields(), crate::schema::Fields::Every(5));
    }

    /// A vector with two values, one of them not a number, was "expected
    /// a vector of two numbers, found an array of 2".
    #[test]
    fn a_vector_names_the_element_that_is_no_number() {
        for (t, what) in [
            ("[-150, \"a\"]", "the second of them the string \"a\""),
            ("[[-150.0], [0.0]]", "the first of them an array of 1"),
        ] {
            let e = load_text("vec2", GOOD, &[&format!("traction.0.t={t}")])
                .unwrap_err()
                .0;
            assert!(
                e.contains("expected a vector of two numbers, found two values")
                    && e.contains(what)
                    && !e.contains("an array of 2"),
                "{t}: {e}"
            );
        }
    }

    /// A value reported as wrong and taken out is not also reported
    /// missing: `mu = nan` added "needs mu = ...", `foundation = 1`
    /// "needs foundation = ...", and `pressure_profile = { sin = .. }`
    /// "missing field `table`" without a line.
    #[test]
    fn a_value_reported_is_not_reported_missing_too() {
        for (sets, what) in [
            (vec!["contact.mu=nan"], "contact.mu holds NaN"),
            (
                vec!["contact.pressure_profile={ sin = { omega = 1 } }"],
                "unknown field `sin` in [contact.pressure_profile]; the keys here are: table",
            ),
            (
                vec![
                    "contact.law=compliance",
                    "contact.cn=1e4",
                    "contact.foundation=1",
                ],
                "contact.foundation: expected a table",
            ),
            (
                vec![
                    "contact.law=compliance",
                    "contact.foundation={ point = [0, 0], normal = [0, 1] }",
                    "contact.cn=\"x\"",
                ],
                "contact.cn: expected a number",
            ),
        ] {
            let text = if sets[0].starts_with("contact.law") {
                GOOD.replace("pressure = 300.0\n", "")
            } else {
                GOOD.to_string()
            };
            let e = load_text("reported", &text, &sets).unwrap_err().0;
            assert!(e.contains(what), "{sets:?}: {e}");
            assert_eq!(e.lines().count(), 1, "{sets:?}: {e}");
        }
        // Still missing where nothing was given.
        let e = load_text("missing-mu", &GOOD.replace("mu = 0.3\n", ""), &[])
            .unwrap_err()
            .0;
        assert!(e.contains("needs mu = ..."), "{e}");
    }

    /// Numbers in messages are short: `{}` wrote 1e99 with a hundred digits.
    #[test]
    fn numbers_in_messages_are_short() {
        let e = load_text("nu-huge", GOOD, &["material.nu=1e99"])
            .unwrap_err()
            .0;
        assert!(
            e.contains("material.nu = 1e99 must lie in (-1, 0.5)"),
            "{e}"
        );
        assert!(e.len() < 300, "{e}");
        let e = load_text("dt-tiny", GOOD, &["time.dt=-2.5e-9"])
            .unwrap_err()
            .0;
        assert!(e.contains("time.dt = -2.5e-9 must be"), "{e}");
        // Ordinary values as written.
        let e = load_text("mu-neg", GOOD, &["contact.mu=-0.3"])
            .unwrap_err()
            .0;
        assert!(e.contains("contact.mu = -0.3 must be"), "{e}");
        assert_eq!(Num(1000.0).to_string(), "1000");
        assert_eq!(Num(2.1e11).to_string(), "2.1e11");
        assert_eq!(Num(0.0).to_string(), "0");
    }

    /// `--set dirichlet=[]` said "dirichlet is a table": it is a list of
    /// tables, which --set cannot replace as a whole.
    #[test]
    fn set_of_a_whole_list_of_tables_names_it_a_list() {
        let e = load_text("set-list", GOOD, &["dirichlet=[]"])
            .unwrap_err()
            .0;
        assert!(
            e.contains("dirichlet is a list of 2 tables ([[dirichlet]])")
                && e.contains("dirichlet.0.KEY=VALUE")
                && !e.contains("is a table"),
            "{e}"
        );
        let e = load_text("set-table", GOOD, &["time=1"]).unwrap_err().0;
        assert!(e.contains("time is a table"), "{e}");
    }

    /// A directory or a device given as the case is named for what it is
    /// (a directory said "cannot read the case file: Is a directory").
    #[test]
    fn a_directory_or_a_device_given_as_the_case_is_named() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
        let e = load(dir, &[]).unwrap_err().0;
        assert!(
            e.contains("is a directory; give the case's .toml file in it"),
            "{e}"
        );
        let e = load(Path::new("/dev/null"), &[]).unwrap_err().0;
        assert!(e.contains("not a regular file"), "{e}");
    }

    /// A reduced step below REDUCTION_MIN_RATIO of Δt is refused by name
    /// (1e-20 with Δt = 1e-3 ran Newmark to its end with an energy of
    /// 8e13); 1e-7, the paper's 1e-4 of Δt, passes.
    #[test]
    fn a_reduced_step_at_round_off_is_refused() {
        let e = load_text(
            "reduction",
            GOOD,
            &["time.stick_reduction={ dt = 1e-20, steps = 10 }"],
        )
        .unwrap_err()
        .0;
        assert!(
            e.contains("time.stick_reduction.dt = 1e-20 is below 1e-9")
                && e.contains("use at least 1.0e-12"),
            "{e}"
        );
        for (dt, ok) in [("1e-7", true), ("1e-12", true), ("0.9e-12", false)] {
            let set = format!("time.stick_reduction={{ dt = {dt}, steps = 10 }}");
            let r = load_text("reduction-bound", GOOD, &[set.as_str()]);
            assert_eq!(r.is_ok(), ok, "{dt}: {r:?}");
        }
    }
}
