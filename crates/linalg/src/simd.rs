//! The one place that knows the CPU: a [`Kernel`] run by [`vectorized`] is
//! compiled once per instruction set faer's `pulp` dispatches to (AVX-512,
//! AVX2 with FMA on x86-64, else the baseline) and run as the CPU allows.
//! Kernels are plain loops, or pulp's safe vector operations on the token
//! they are handed; every function they call is `#[inline(always)]` so that
//! it is compiled inside the dispatched one. Rust never contracts a product
//! and a sum into a fused multiply-add: a kernel fuses only where it asks
//! to (`mul_add`), and then on every path, the scalar one included, so the
//! same bits on every CPU.

pub use pulp::Simd;

/// A loop to compile for the CPU's instruction set. `run` and what it
/// calls must be `#[inline(always)]`.
pub trait Kernel {
    /// What the loop returns.
    type Output;
    /// The loop, with the instruction set's token for pulp's operations.
    fn run<S: Simd>(self, simd: S) -> Self::Output;
}

struct Dispatched<K>(K);

impl<K: Kernel> pulp::WithSimd for Dispatched<K> {
    type Output = K::Output;

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> K::Output {
        self.0.run(simd)
    }
}

/// Runs `kernel` compiled for the best instruction set this CPU has.
#[inline(always)]
pub fn vectorized<K: Kernel>(kernel: K) -> K::Output {
    pulp::Arch::new().dispatch(Dispatched(kernel))
}

/// The vector of `S::F64_LANES` doubles at the start of `v` (which holds
/// exactly that many).
#[inline(always)]
pub fn load<S: Simd>(v: &[f64]) -> S::f64s {
    pulp::bytemuck::pod_read_unaligned(pulp::bytemuck::cast_slice(v))
}

/// Stores `s` into `out` (exactly `S::F64_LANES` doubles).
#[inline(always)]
pub fn store<S: Simd>(out: &mut [f64], s: S::f64s) {
    out.copy_from_slice(pulp::bytemuck::cast_slice(std::slice::from_ref(&s)));
}

/// (x1, x0, x3, x2, …): each pair of lanes swapped, by one in-lane
/// permute on AVX and AVX-512 (pulp's safe intrinsics, on the token's
/// instruction set), else lane by lane.
#[inline(always)]
pub fn swap_pairs<S: Simd>(simd: S, x: S::f64s) -> S::f64s {
    use pulp::bytemuck::cast;
    use std::any::Any;
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m256d, __m512d};
        if let Some(v4) = (&simd as &dyn Any).downcast_ref::<pulp::x86::V4>() {
            return cast(v4.avx512f._mm512_permute_pd::<0x55>(cast::<_, __m512d>(x)));
        }
        if let Some(v3) = (&simd as &dyn Any).downcast_ref::<pulp::x86::V3>() {
            return cast(v3.avx._mm256_permute_pd::<0b0101>(cast::<_, __m256d>(x)));
        }
    }
    let mut v = x;
    let lanes: &mut [f64] = pulp::bytemuck::cast_slice_mut(std::slice::from_mut(&mut v));
    for pair in lanes.chunks_exact_mut(2) {
        pair.swap(0, 1);
    }
    v
}

/// Doubles per vector register of the instruction set [`vectorized`]
/// runs kernels with on this CPU.
pub fn lanes() -> usize {
    struct Lanes;
    impl Kernel for Lanes {
        type Output = usize;
        #[inline(always)]
        fn run<S: Simd>(self, _simd: S) -> usize {
            S::F64_LANES
        }
    }
    vectorized(Lanes)
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
