//! Handing freed heap back to the operating system after setup.
//!
//! Setup (assembly, the critical-step estimate, the compact K's dictionary,
//! a factorization's workspace) allocates and frees large temporaries.
//! glibc's allocator raises its mmap threshold as such blocks are freed, so
//! later ones of a similar size come from the heap, and once freed they
//! stay resident unless the heap is trimmed: measured on the 251k-DOF Q1
//! slab (central difference), 23 MB of a 71 MB run phase were such free
//! memory (peak over need 1.71 before, 1.16 after `malloc_trim`). The step
//! loop allocates nothing (tests/no_alloc.rs), so trimming once after each
//! of those phases keeps the run's resident memory at what it holds.
//!
//! `malloc_trim` does not shrink the top of a thread's arena, though, and
//! setup's parallel parts allocate in the pool's threads' arenas: on the
//! Q2 352×88 slab (central difference) about one run in four held 13.4 MB
//! more at the run's start, free memory at the top of a worker's arena
//! (its mapping 37.8 against 24.3 MB resident; peak over need 1.66 against
//! 1.26, 2026-11-25). glibc trims a thread arena's top when a free leaves
//! more than its trim threshold there, but raises that threshold (to twice
//! the largest mapped block freed, up to 64 MiB) as setup frees large
//! blocks. [`fix_thresholds`] fixes it at 1 MiB: 16 of 16 runs with the
//! same settings made by glibc's environment variables started at
//! 42.9-43.2 MB (peak over need 1.25-1.26), 8 of 8 with this function at
//! 43.1-43.3 MB, setup 2.09-2.64 s as before, the Q2 1M step the same
//! within the host's noise (three alternating pairs). Fixing a threshold turns off glibc's adjusting of both, so
//! the mmap threshold is fixed too, at the most it would adjust to (32
//! MiB): at 1 MiB every vector of the step would be a mapping of its own,
//! all starting 16 bytes into a page, and the step's streams then alias
//! in the core's 4 KiB address checks (Q2 1M step 2.69-3.09 against
//! 2.36-2.78 ms, four alternating pairs of runs).

/// glibc's thresholds ([`fix_thresholds`]): trim at 1 MiB, mmap from 32 MiB.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const THRESHOLDS: [(std::ffi::c_int, std::ffi::c_int); 2] = [
    // M_TRIM_THRESHOLD.
    (-1, 1 << 20),
    // M_MMAP_THRESHOLD.
    (-3, 32 << 20),
];

/// Fixes glibc's trim threshold at 1 MiB and its mmap threshold at 32 MiB
/// (module documentation), once per process; a no-op elsewhere. Call
/// before large allocations: the binaries call it first thing,
/// `Integrator::new` again for library users.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[allow(unsafe_code)]
pub fn fix_thresholds() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    extern "C" {
        fn mallopt(param: std::ffi::c_int, value: std::ffi::c_int) -> std::ffi::c_int;
    }
    // SAFETY: mallopt only changes the allocator's parameters; glibc takes
    // its lock for it, so any thread may call it at any time.
    ONCE.call_once(|| {
        for (param, value) in THRESHOLDS {
            unsafe { mallopt(param, value) };
        }
    });
}

/// Fixes glibc's thresholds (a no-op without glibc).
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn fix_thresholds() {}

/// Returns free heap memory to the system (glibc's `malloc_trim(0)`); a
/// no-op elsewhere. Costs a walk over the heap's free lists: call it after
/// setup phases, not per step.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[allow(unsafe_code)]
pub(crate) fn release_free_memory() {
    extern "C" {
        fn malloc_trim(pad: usize) -> std::ffi::c_int;
    }
    // SAFETY: malloc_trim has no preconditions: it only releases memory the
    // allocator holds as free, and may be called at any time from any thread.
    unsafe {
        malloc_trim(0);
    }
}

/// Returns free heap memory to the system (glibc's `malloc_trim(0)`); a
/// no-op elsewhere.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub(crate) fn release_free_memory() {}
