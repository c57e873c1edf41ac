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
//! setup's parallel parts allocate in the pool's threads' arenas. On the
//! Q2 352×88 slab (central difference) about one run in four held 13.4 MB
//! more at the run's start, free memory at the top of a worker's arena
//! (its mapping 37.8 against 24.3 MB resident; peak over need 1.66 against
//! 1.26, 2026-11-25). glibc trims such a top when a free leaves more than
//! its trim threshold there, but raises that threshold as setup frees
//! large mapped blocks. So [`release_free_memory`] also fixes the trim
//! threshold at 1 MiB and frees a block on each pool thread, which trims
//! its arena's top: 24 of 24 runs of that slab at 1.255-1.270, the Q1
//! 352×88 slab's run start 17.9 → 14.5 MB, the Newmark rungs of 250k DOFs
//! 1.228-1.237 (1.228-1.279 before), step times as before within the
//! host's noise (alternating runs). Fixing the thresholds from the start
//! instead was tried and not kept: trim at 1 MiB with mmap from 32 MiB
//! left the freed CSR of the Q1 352×88 slab resident in the main heap
//! (run start 17.9 → 32.4 MB); mmap from 1 MiB maps every step vector at
//! the same page offset, and the Q2 1M step was about 10% slower (the
//! streams alias in the core's 4 KiB address checks).

/// Returns free heap memory to the system (glibc's `malloc_trim(0)`, and
/// the tops of the pool threads' arenas: module documentation); a no-op
/// elsewhere. Costs a walk over the heap's free lists and a task on each
/// pool thread: call it after setup phases, not per step.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[allow(unsafe_code)]
pub(crate) fn release_free_memory() {
    extern "C" {
        fn malloc_trim(pad: usize) -> std::ffi::c_int;
        fn mallopt(param: std::ffi::c_int, value: std::ffi::c_int) -> std::ffi::c_int;
    }
    /// glibc's M_TRIM_THRESHOLD.
    const M_TRIM_THRESHOLD: std::ffi::c_int = -1;
    // SAFETY: mallopt only changes the allocator's parameters (under its
    // lock); it leaves the mmap threshold where glibc has raised it.
    unsafe {
        mallopt(M_TRIM_THRESHOLD, 1 << 20);
    }
    // A block freed next to the top of each pool thread's arena makes glibc
    // trim that top (malloc_trim does not).
    rayon::broadcast(|_| {
        let block: Vec<u8> = Vec::with_capacity(64 << 10);
        drop(std::hint::black_box(block));
    });
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
