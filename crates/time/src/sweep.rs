//! The explicit step's passes over the free-DOF vectors (METHOD.md §4 with
//! β = 0 and the lumped mass).
//!
//! An explicit step is bound by memory traffic, so it makes two sweeps: the
//! predictor r_K = r + Δt ṙ + ½Δt² r̈ ([`predict`], with R_K formed only on
//! the rows where a load is nonzero, [`SparseLoads`]); then, once r_K
//! exists everywhere, one sweep ([`sweep`]) that forms K r_K by batches
//! that stay in L1, R̂_K, ṙ_K = R̂_K/(m·scale) (or, at the contact DOFs,
//! the velocity the nodal friction gave, formed before the sweep), r̈_K and
//! the strain and kinetic sums. All passes run in the fixed chunks of
//! `stickslip_linalg::chunks`: the same bits on any number of threads.

use stickslip_linalg::chunks::{each_chunk, each_chunk_pair, CHUNK};
use stickslip_linalg::Product;

/// The loads on the rows where the constant load or any load vector is
/// nonzero (bit for bit: a −0 counts): tractions act on a boundary, so a
/// few rows. Elsewhere R_K = +0 + Σ θ_l·(+0) = +0 exactly for finite θ_l,
/// and those rows of R_K are never written.
#[derive(Clone, Debug)]
pub(crate) struct SparseLoads {
    /// Rows, ascending.
    rows: Vec<usize>,
    /// The constant load on them.
    constant: Vec<f64>,
    /// Each load vector on them.
    loads: Vec<Vec<f64>>,
}

impl SparseLoads {
    /// The loads `constant` and `loads` (vectors of one length) on their
    /// nonzero rows.
    pub fn new(constant: &[f64], loads: &[&[f64]]) -> SparseLoads {
        let rows: Vec<usize> = (0..constant.len())
            .filter(|&i| constant[i].to_bits() != 0 || loads.iter().any(|l| l[i].to_bits() != 0))
            .collect();
        SparseLoads {
            constant: rows.iter().map(|&i| constant[i]).collect(),
            loads: loads
                .iter()
                .map(|l| rows.iter().map(|&i| l[i]).collect())
                .collect(),
            rows,
        }
    }

    /// Bytes a step moves for them: the row indices and the loads read,
    /// R_K written, R_{K−1}, r and r_K read at those rows.
    pub fn bytes(&self) -> usize {
        self.rows.len() * (8 + 8 * (1 + self.loads.len()) + 8 * 4)
    }
}

/// Per-chunk sums of the sweep: [kinetic, not finite, strain].
pub(crate) type Partials = Vec<[f64; 3]>;

/// The predictor r_K = r + c1 ṙ + c2 r̈ into `r_new` (every row), and
/// R_K = constant + Σ θ_l load_l into `load_new` at the loads' rows only
/// (its other rows hold +0), with the work Σ ½(R_K + R_{K−1})(r_K −
/// r_{K−1}) and r_K·R_K over those rows: a row off the loads would add
/// ½(+0)(r_K − r) = ±0, and a sum that starts at +0 is never −0, so
/// leaving those rows out changes no bit. Every θ_l must be finite.
/// Returns (work, r_K·R_K).
#[allow(clippy::too_many_arguments)]
pub(crate) fn predict(
    sparse: &SparseLoads,
    thetas: &[f64],
    [r, v, a]: [&[f64]; 3],
    [c1, c2]: [f64; 2],
    load: &[f64],
    load_new: &mut [f64],
    r_new: &mut [f64],
) -> (f64, f64) {
    debug_assert!(thetas.iter().all(|t| t.is_finite()));
    each_chunk(r_new, |c, rn| {
        let range = c * CHUNK..c * CHUNK + rn.len();
        let (r, v, a) = (&r[range.clone()], &v[range.clone()], &a[range]);
        for i in 0..rn.len() {
            rn[i] = r[i] + c1 * v[i] + c2 * a[i];
        }
    });
    let (mut work, mut dot) = (0.0, 0.0);
    for (k, &i) in sparse.rows.iter().enumerate() {
        let mut l = sparse.constant[k];
        for (load, &theta) in sparse.loads.iter().zip(thetas) {
            if theta != 0.0 {
                l += theta * load[k];
            }
        }
        load_new[i] = l;
        work += 0.5 * (l + load[i]) * (r_new[i] - r[i]);
        dot += r_new[i] * l;
    }
    (work, dot)
}

/// The vectors and coefficients of one sweep.
pub(crate) struct StepData<'a> {
    /// R_K (+0 off the load rows).
    pub load_new: &'a [f64],
    /// Lumped mass.
    pub mass: &'a [f64],
    /// r_K (the predictor, final for β = 0).
    pub r_new: &'a [f64],
    /// ṙ_{K−1}.
    pub v: &'a [f64],
    /// r̈_{K−1}.
    pub a: &'a [f64],
    /// Coefficients of R̂_K: 1/(γΔt) and 1/γ − 1.
    pub cv: f64,
    /// See `cv`.
    pub ca: f64,
    /// 1/(γΔt): ṙ_K = b/(m·scale), r̈_K = (ṙ_K − ṙ)·scale − ratio·r̈.
    pub scale: f64,
    /// (1−γ)/γ.
    pub ratio: f64,
}

impl StepData<'_> {
    /// R̂_K at row i from its K r_K: R_K − K r_K + m(cv ṙ + ca r̈)
    /// (METHOD.md §4 with the lumped mass).
    #[inline(always)]
    pub fn rhs(&self, i: usize, ku: f64) -> f64 {
        self.load_new[i] - ku + self.mass[i] * (self.cv * self.v[i] + self.ca * self.a[i])
    }
}

/// What the sweep sums.
pub(crate) struct Sums {
    /// ½ r_Kᵀ K r_K.
    pub strain: f64,
    /// ½ ṙ_Kᵀ M_L ṙ_K.
    pub kinetic: f64,
    /// Every entry of r_K and ṙ_K is finite.
    pub finite: bool,
}

/// A sum over rows in four lanes, row i in lane i mod 4, added
/// (l0 + l1) + (l2 + l3) at the end: four chains of additions instead of
/// one, in an order fixed by the rows whatever batch or thread adds them.
#[derive(Clone, Copy, Default)]
struct Lanes([f64; 4]);

impl Lanes {
    /// Adds term(a[k], b[k]) for rows i0 + k.
    #[inline(always)]
    fn add_pairs(&mut self, i0: usize, a: &[f64], b: &[f64], term: impl Fn(f64, f64) -> f64) {
        let n = a.len().min(b.len());
        let (a, b) = (&a[..n], &b[..n]);
        let mut lanes = self.0;
        let head = ((4 - i0 % 4) % 4).min(n);
        for k in 0..head {
            lanes[(i0 + k) % 4] += term(a[k], b[k]);
        }
        let (mut a4, mut b4) = (a[head..].chunks_exact(4), b[head..].chunks_exact(4));
        for (x, y) in (&mut a4).zip(&mut b4) {
            for l in 0..4 {
                lanes[l] += term(x[l], y[l]);
            }
        }
        // Past the whole quads row i0 + k sits in lane k.
        for (l, (x, y)) in a4.remainder().iter().zip(b4.remainder()).enumerate() {
            lanes[l] += term(*x, *y);
        }
        self.0 = lanes;
    }

    fn total(self) -> f64 {
        (self.0[0] + self.0[1]) + (self.0[2] + self.0[3])
    }
}

/// The sweep: per row, K r_K, R̂_K, ṙ_K = R̂_K/(m·scale) — or, at the
/// contact DOFs, the velocity the nodal friction gave (`friction`, (DOF,
/// ṙ_K) sorted by DOF) — then r̈_K into `a_new` and the sums. K r_K comes
/// in batches that stay in L1 ([`Product::batches`]), and each batch's
/// rows go in loops over the batch: no dependence between rows, so their
/// divisions overlap.
pub(crate) fn sweep(
    k: &Product,
    s: &StepData,
    friction: &[(usize, f64)],
    v_new: &mut [f64],
    a_new: &mut [f64],
    partials: &mut Partials,
) -> Sums {
    let [kinetic, not_finite, strain] = each_chunk_pair(v_new, a_new, partials, |c, vn, an, p| {
        let start = c * CHUNK;
        let mut f = friction.partition_point(|f| f.0 < start);
        let (mut strain, mut kinetic) = (Lanes::default(), Lanes::default());
        let mut finite = true;
        k.batches(c, s.r_new, |r0, ku| {
            let rows = r0..r0 + ku.len();
            let (m, rn) = (&s.mass[rows.clone()], &s.r_new[rows.clone()]);
            let (v, a) = (&s.v[rows.clone()], &s.a[rows.clone()]);
            let vn = &mut vn[r0 - start..r0 - start + ku.len()];
            let an = &mut an[r0 - start..r0 - start + ku.len()];
            for j in 0..ku.len() {
                vn[j] = s.rhs(r0 + j, ku[j]) / (m[j] * s.scale);
            }
            while f < friction.len() && friction[f].0 < rows.end {
                vn[friction[f].0 - r0] = friction[f].1;
                f += 1;
            }
            for j in 0..ku.len() {
                an[j] = (vn[j] - v[j]) * s.scale - s.ratio * a[j];
                // `&`, not `&&`: no branch, so the loop stays vectorized.
                finite &= rn[j].is_finite() & vn[j].is_finite();
            }
            strain.add_pairs(r0, rn, ku, |r, u| r * u);
            kinetic.add_pairs(r0, m, vn, |m, v| m * v * v);
        });
        *p = [
            kinetic.total(),
            if finite { 0.0 } else { 1.0 },
            strain.total(),
        ];
    });
    Sums {
        strain: 0.5 * strain,
        kinetic: 0.5 * kinetic,
        finite: not_finite == 0.0,
    }
}
