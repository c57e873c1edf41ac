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
//! Not covered: `malloc_trim` does not shrink the top of a thread's arena,
//! and setup's parallel parts allocate in the pool's threads' arenas. On
//! the Q2 352×88 slab (central difference) about one run in four held
//! 13.4 MB more at the run's start, free memory at the top of a worker's
//! arena (its mapping 37.8 against 24.3 MB resident; peak over need 1.66
//! against 1.26, 2026-11-25). glibc trims such a top when a free leaves
//! more than its trim threshold there, but raises that threshold as setup
//! frees large mapped blocks. Fixing the thresholds (`mallopt`) was tried
//! and not kept: trim at 1 MiB with mmap from 32 MiB kept every run at
//! 1.25-1.27 (24 runs) but left the freed CSR of the Q1 352×88 slab
//! resident in the main heap (17.9 → 32.4 MB at the run's start); mmap
//! from 1 MiB gave 1.06 in 20 runs but maps every step vector at the same
//! page offset, and the Q2 1M step was about 10% slower (the streams alias
//! in the core's 4 KiB address checks).

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
