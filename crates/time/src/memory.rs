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
