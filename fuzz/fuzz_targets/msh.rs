//! Any bytes given to the .msh reader give `Ok` or a typed `Err`, never a
//! panic, an abort or an allocation the input size does not justify.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = stickslip_mesh::Mesh::from_bytes(data);
});
