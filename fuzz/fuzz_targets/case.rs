//! Any text given to the case reader (with any `--set` overrides) gives a
//! `Case` or an `InputError` naming what is wrong, never a panic; so does
//! the restart comparison of two case texts.
//!
//! Input layout: the case text, then optionally a NUL byte followed by
//! `--set` arguments, one per line.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let (case, sets) = text.split_once('\0').unwrap_or((text, ""));
    let sets: Vec<String> = sets.lines().take(8).map(str::to_string).collect();
    let path = std::path::Path::new("fuzz/case.toml");
    let _ = stickslip_case::load_str(path, case, &sets);
    let _ = stickslip_case::restart_changes(case, case);
    let _ = stickslip_case::restart_changes(case, "title = \"x\"\n");
});
