//! The one place that knows the CPU: a [`Kernel`] run by [`vectorized`] is
//! compiled once per instruction set faer's `pulp` dispatches to (AVX2 with
//! FMA on x86-64, else the baseline) and run as the CPU allows. Kernels are
//! plain loops, every function they call `#[inline(always)]` so that it is
//! compiled inside the dispatched one; the compiler then vectorizes them
//! wider where the features allow, with the same IEEE operations (Rust
//! never contracts a product and a sum into a fused multiply-add), so the
//! same bits on every CPU.

/// A loop to compile for the CPU's instruction set. `run` and what it
/// calls must be `#[inline(always)]`.
pub trait Kernel {
    /// What the loop returns.
    type Output;
    /// The loop.
    fn run(self) -> Self::Output;
}

struct Dispatched<K>(K);

impl<K: Kernel> pulp::WithSimd for Dispatched<K> {
    type Output = K::Output;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> K::Output {
        self.0.run()
    }
}

/// Runs `kernel` compiled for the best instruction set this CPU has.
#[inline(always)]
pub fn vectorized<K: Kernel>(kernel: K) -> K::Output {
    pulp::Arch::new().dispatch(Dispatched(kernel))
}

/// What a product hands each batch of rows to ([`crate::Product::batches`]).
pub trait Batches {
    /// K x on rows r0..r0 + ku.len().
    fn batch(&mut self, r0: usize, ku: &[f64]);
}

impl<F: FnMut(usize, &[f64])> Batches for F {
    #[inline(always)]
    fn batch(&mut self, r0: usize, ku: &[f64]) {
        self(r0, ku)
    }
}
