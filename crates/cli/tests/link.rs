//! How the binary links HDF5 (crates/cli/build.rs).

use std::process::Command;

/// Where the build linked Debian's static HDF5, the binary loads no
/// libhdf5, and none of the libraries the shared one pulls in (libcurl,
/// OpenSSL, GnuTLS, Kerberos, szip, zlib): `ldd` lists what the dynamic
/// loader would load. The link relies on Cargo passing the package's own
/// library search path before hdf5-metno-sys's; this fails if that
/// changes. Under CI (Debian's libhdf5-dev, installed by `cargo xtask`)
/// the build must have found the archives.
#[test]
fn hdf5_is_linked_statically_where_its_archive_is() {
    if env!("STICKSLIP_HDF5_LINKED") != "static" {
        assert!(
            std::env::var_os("CI").is_none(),
            "the build found no static libhdf5.a (with libsz.a, libaec.a, libz.a): is libhdf5-dev installed?"
        );
        eprintln!("skipped: HDF5 is linked as a shared library (no libhdf5.a found at build time)");
        return;
    }
    let o = match Command::new("ldd")
        .arg(env!("CARGO_BIN_EXE_stickslip"))
        .output()
    {
        Ok(o) => o,
        Err(e) => {
            assert!(std::env::var_os("CI").is_none(), "cannot run ldd: {e}");
            eprintln!("skipped: no ldd ({e})");
            return;
        }
    };
    assert!(o.status.success(), "ldd failed: {o:?}");
    let loaded = String::from_utf8_lossy(&o.stdout);
    for lib in [
        "libhdf5",
        "libcurl",
        "libssl",
        "libcrypto",
        "libgnutls",
        "libkrb5",
        "libldap",
        "libsz",
        "libaec",
        "libz.",
    ] {
        assert!(!loaded.contains(lib), "the binary loads {lib}:\n{loaded}");
    }
    // The C library is still there: ldd listed the binary's libraries.
    assert!(loaded.contains("libc.so"), "{loaded}");
}
