//! The explicit step's passes over the free-DOF vectors (METHOD.md §4 with
//! β = 0 and the lumped mass).
//!
//! An explicit step is bound by memory traffic, so it makes one sweep over
//! the vectors ([`sweep`]): once the predictor r_K = r + Δt ṙ + ½Δt² r̈
//! exists everywhere, it forms K r_K by batches that stay in L1, R̂_K,
//! ṙ_K = R̂_K/(m·scale) (or, at the contact DOFs, the velocity the nodal
//! friction gave, formed before the sweep), r̈_K, the strain and kinetic
//! sums, and the next step's predictor r_K + Δt ṙ_K + ½Δt² r̈_K with
//! [`predict`]'s operations: a next step of the same Δt skips that pass
//! and only forms R_K on the rows where a load is nonzero ([`loads_at`],
//! [`SparseLoads`]); the sweep reads R_K on those rows only. Streams per
//! step: the sweep reads r_K, m, ṙ, r̈ and writes ṙ_K, r̈_K, r_{K+1}. All
//! passes run in the fixed chunks of `stickslip_linalg::chunks`: the same
//! bits on any number of threads.
//!
//! With Rayleigh damping (METHOD.md §8) the sweep takes another path, row
//! by row, only then: the mass part divides by m·(1/(γΔt) + α) (centred,
//! exact), the stiffness part is the force (β/Δt)(K r_K − K r_{K−1}) of the
//! half-step velocity, K r_{K−1} kept from the last sweep (which writes
//! K r_K for the next), and the damping's dissipation is summed alongside.
//! The undamped path is untouched: no extra stream, no extra sum.

use stickslip_linalg::chunks::{each_chunk, each_chunk_of, CHUNK};
use stickslip_linalg::simd::{load, store, vectorized, Batches, Kernel, Simd};
use stickslip_linalg::Formed;

/// The loads on the rows where the constant load or any load vector is
/// nonzero (bit for bit: a −0 counts): tractions act on a boundary, so a
/// few rows. Elsewhere R_K = +0 + Σ θ_l·(+0) = +0 exactly for finite θ_l,
/// and those rows of R_K are never written.
#[derive(Clone, Debug, Default)]
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

    /// The rows, ascending.
    pub fn rows(&self) -> &[usize] {
        &self.rows
    }

    /// Bytes a step moves for them: the row indices and the loads read,
    /// R_K written, R_{K−1}, r and r_K read at those rows.
    pub fn bytes(&self) -> usize {
        self.rows.len() * (8 + 8 * (1 + self.loads.len()) + 8 * 4)
    }
}

/// Per-chunk sums of the sweep: [kinetic, not finite, strain, the
/// damping's mass part Σ m ṙ̄², its stiffness part Σ (K r_K − K r_{K−1})
/// (ṙ + ½Δt r̈)].
pub(crate) type Partials = Vec<[f64; 5]>;

/// The predictor r_K = r + c1 ṙ + c2 r̈ into `r_new` (every row).
pub(crate) fn predict([r, v, a]: [&[f64]; 3], [c1, c2]: [f64; 2], r_new: &mut [f64]) {
    each_chunk(r_new, |c, rn| {
        let range = c * CHUNK..c * CHUNK + rn.len();
        let (r, v, a) = (&r[range.clone()], &v[range.clone()], &a[range]);
        for i in 0..rn.len() {
            rn[i] = r[i] + c1 * v[i] + c2 * a[i];
        }
    });
}

/// R_K = constant + Σ θ_l load_l into `load_new` at the loads' rows only
/// (its other rows hold +0), with the work Σ ½(R_K + R_{K−1})(r_K −
/// r_{K−1}) and r_K·R_K over those rows: a row off the loads would add
/// ½(+0)(r_K − r) = ±0, and a sum that starts at +0 is never −0, so
/// leaving those rows out changes no bit. Every θ_l must be finite.
/// Returns (work, r_K·R_K).
pub(crate) fn loads_at(
    sparse: &SparseLoads,
    thetas: &[f64],
    [r, r_new]: [&[f64]; 2],
    load: &[f64],
    load_new: &mut [f64],
) -> (f64, f64) {
    debug_assert!(thetas.iter().all(|t| t.is_finite()));
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
    /// The rows where R_K may be other than +0, ascending.
    pub load_rows: &'a [usize],
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
    /// 1/(γΔt): r̈_K = (ṙ_K − ṙ)·scale − ratio·r̈.
    pub scale: f64,
    /// ṙ_K = R̂_K/(m·dscale): `scale`, plus α with mass-proportional
    /// damping.
    pub dscale: f64,
    /// The stiffness-proportional damping's data, with damping on.
    pub damped: Option<Damped<'a>>,
    /// (1−γ)/γ.
    pub ratio: f64,
    /// The predictor's coefficients for the next step: Δt and ½Δt².
    pub next: [f64; 2],
}

/// What a damped sweep reads besides the undamped one's.
pub(crate) struct Damped<'a> {
    /// K r_{K−1}.
    pub ku_prev: &'a [f64],
    /// β/Δt: the stiffness part's force is bs·(K r_K − K r_{K−1}).
    pub bs: f64,
}

impl StepData<'_> {
    /// R̂_K at row i from its K r_K: R_K − K r_K + m(cv ṙ + ca r̈)
    /// (METHOD.md §4 with the lumped mass), less the stiffness-proportional
    /// damping force with damping on.
    #[inline(always)]
    pub fn rhs(&self, i: usize, ku: f64) -> f64 {
        let rhs =
            self.load_new[i] - ku + self.mass[i] * (self.cv * self.v[i] + self.ca * self.a[i]);
        match &self.damped {
            None => rhs,
            Some(d) => rhs - d.bs * (ku - d.ku_prev[i]),
        }
    }
}

/// What the sweep sums.
pub(crate) struct Sums {
    /// ½ r_Kᵀ K r_K.
    pub strain: f64,
    /// ½ ṙ_Kᵀ M_L ṙ_K.
    pub kinetic: f64,
    /// With damping: (Σ m ṙ̄², Σ (K r_K − K r_{K−1})(ṙ + ½Δt r̈)), ṙ̄ =
    /// ½(ṙ_K + ṙ); zeros without.
    pub damped: [f64; 2],
    /// Every entry of r_K and ṙ_K is finite.
    pub finite: bool,
}

/// Rows per block of the sweep's sums: row i adds to lane i mod 8, and
/// the lanes are added in a fixed tree at the end, so the sums have the
/// same bits whatever the CPU's vector width, batch or thread.
const LANES: usize = 8;

/// A sum over rows in [`LANES`] lanes.
#[derive(Clone, Copy)]
struct Lanes([f64; LANES]);

impl Lanes {
    #[inline(always)]
    fn total(self) -> f64 {
        let l = self.0;
        ((l[0] + l[1]) + (l[2] + l[3])) + ((l[4] + l[5]) + (l[6] + l[7]))
    }
}

/// The sweep: per row, K r_K, R̂_K, ṙ_K = R̂_K/(m·scale) — or, at the
/// contact DOFs, the velocity the nodal friction gave (`friction`, (DOF,
/// ṙ_K) sorted by DOF) — then r̈_K into `a_new`, the next predictor into
/// `r_next` and the sums. R̂_K is formed with R_K = +0 (the same bits as
/// from the +0 stored there) and again at the load rows. K r_K comes
/// in batches that stay in L1 ([`Formed::batches`]), and each batch's
/// rows go in loops over the batch: no dependence between rows, so their
/// divisions overlap. Each chunk is a dispatched kernel
/// (`stickslip_linalg::simd`).
pub(crate) fn sweep(
    k: &Formed,
    s: &StepData,
    friction: &[(usize, f64)],
    [v_new, a_new, r_next]: [&mut [f64]; 3],
    ku_new: Option<&mut [f64]>,
    partials: &mut Partials,
) -> Sums {
    let [kinetic, not_finite, strain, mass_part, stiffness_part] = match ku_new {
        None => each_chunk_of([v_new, a_new, r_next], partials, |c, [vn, an, rx], p| {
            *p = chunk(k, s, friction, c, [vn, an, rx], None);
        }),
        Some(ku) => each_chunk_of(
            [v_new, a_new, r_next, ku],
            partials,
            |c, [vn, an, rx, ku], p| {
                *p = chunk(k, s, friction, c, [vn, an, rx], Some(ku));
            },
        ),
    };
    Sums {
        strain: 0.5 * strain,
        kinetic: 0.5 * kinetic,
        damped: [mass_part, stiffness_part],
        finite: not_finite == 0.0,
    }
}

/// Chunk `c` of [`sweep`] (its outputs' rows, and K r_K's where kept).
fn chunk(
    k: &Formed,
    s: &StepData,
    friction: &[(usize, f64)],
    c: usize,
    [vn, an, rx]: [&mut [f64]; 3],
    ku: Option<&mut [f64]>,
) -> [f64; 5] {
    let start = c * CHUNK;
    vectorized(Chunk {
        k,
        c,
        rows: ChunkRows {
            s,
            friction,
            next: friction.partition_point(|f| f.0 < start),
            next_load: s.load_rows.partition_point(|&i| i < start),
            start,
            vn,
            an,
            rx,
            ku,
        },
    })
}

/// One chunk of the sweep, as a dispatched kernel.
struct Chunk<'a, 'b> {
    k: &'a Formed<'a>,
    c: usize,
    rows: ChunkRows<'a, 'b>,
}

impl Kernel for Chunk<'_, '_> {
    type Output = [f64; 5];

    #[inline(always)]
    fn run<S: Simd>(self, simd: S) -> [f64; 5] {
        let mut rows = Aligned {
            simd,
            rows: self.rows,
            pending: [0.0; LANES],
            held: 0,
            strain: [simd.splat_f64s(0.0); LANES],
            kinetic: [simd.splat_f64s(0.0); LANES],
            finite: simd.splat_f64s(0.0),
            damped_sums: [0.0; 5],
        };
        self.k.batches(simd, self.c, &mut rows);
        rows.finish()
    }
}

/// The per-row work of a chunk of the sweep: its rows, and where its
/// sums go.
struct ChunkRows<'a, 'b> {
    s: &'a StepData<'a>,
    friction: &'a [(usize, f64)],
    /// The next entry of `friction` at or after the rows to come.
    next: usize,
    /// The next load row at or after the rows to come.
    next_load: usize,
    start: usize,
    vn: &'b mut [f64],
    an: &'b mut [f64],
    /// The next step's predictor.
    rx: &'b mut [f64],
    /// K r_K, kept for the next step's damping (damped sweeps only).
    ku: Option<&'b mut [f64]>,
}

impl ChunkRows<'_, '_> {
    /// Row i alone from its K r_K: ṙ_K (or the friction's, at a contact
    /// DOF), r̈_K and the next predictor written; returns ṙ_K.
    #[inline(always)]
    fn row(&mut self, i: usize, ku: f64) -> f64 {
        let s = self.s;
        let l = i - self.start;
        let mut vi = s.rhs(i, ku) / (s.mass[i] * s.dscale);
        if self.next < self.friction.len() && self.friction[self.next].0 == i {
            vi = self.friction[self.next].1;
            self.next += 1;
        }
        let ai = (vi - s.v[i]) * s.scale - s.ratio * s.a[i];
        self.vn[l] = vi;
        self.an[l] = ai;
        self.rx[l] = s.r_new[i] + s.next[0] * vi + s.next[1] * ai;
        vi
    }
}

/// [`ChunkRows`] fed in blocks of [`LANES`] rows aligned to the chunk's
/// start (a multiple of [`LANES`]): K r_K of the rows of an unfinished
/// block is held until the next batch completes it. The sums' lanes sit in
/// `LANES / W` vectors of W doubles.
struct Aligned<'a, 'b, S: Simd> {
    simd: S,
    rows: ChunkRows<'a, 'b>,
    /// K r_K of the first `held` rows of an unfinished block.
    pending: [f64; LANES],
    held: usize,
    strain: [S::f64s; LANES],
    kinetic: [S::f64s; LANES],
    /// Σ 0·r_K + 0·ṙ_K: ±0 while every entry is finite, else NaN.
    finite: S::f64s,
    /// A damped sweep's sums, row by row ([`Partials`]' order).
    damped_sums: [f64; 5],
}

impl<S: Simd> Aligned<'_, '_, S> {
    /// Rows `r0..r0 + ku.len()` (a whole number of vectors of W rows, from
    /// a multiple of [`LANES`]): ṙ_K, r̈_K and the sums.
    #[inline(always)]
    fn rows(&mut self, r0: usize, ku: &[f64]) {
        let (simd, w) = (self.simd, S::F64_LANES);
        let rows = &mut self.rows;
        let s = rows.s;
        let n = ku.len();
        let range = r0..r0 + n;
        let local = r0 - rows.start..r0 - rows.start + n;
        let (m, rn) = (&s.mass[range.clone()], &s.r_new[range.clone()]);
        let (v, a) = (&s.v[range.clone()], &s.a[range.clone()]);
        let (vn, an, rx) = (
            &mut rows.vn[local.clone()],
            &mut rows.an[local.clone()],
            &mut rows.rx[local],
        );
        let splat = |x: f64| simd.splat_f64s(x);
        let (cv, ca, scale, ratio) = (splat(s.cv), splat(s.ca), splat(s.scale), splat(s.ratio));
        let dscale = splat(s.dscale);
        let (c1, c2) = (splat(s.next[0]), splat(s.next[1]));
        let zero = splat(0.0);
        // One pass over the rows, w at a time: their ṙ_K, the load and
        // friction rows among them put in, then r̈_K, the predictor and the
        // sums (each block's vectors k in lanes k·w...), the operands
        // loaded once.
        let (mut strain, mut kinetic, mut finite) = (self.strain, self.kinetic, self.finite);
        for j in (0..n).step_by(w) {
            let (at, k) = (j..j + w, j % LANES / w);
            let (mj, vj, aj) = (
                load::<S>(&m[at.clone()]),
                load::<S>(&v[at.clone()]),
                load::<S>(&a[at.clone()]),
            );
            let (kj, rnj) = (load::<S>(&ku[at.clone()]), load::<S>(&rn[at.clone()]));
            // R̂_K as StepData::rhs forms it from R_K = +0, then ṙ_K =
            // R̂_K/(m·dscale).
            let rhs = simd.add_f64s(
                simd.sub_f64s(zero, kj),
                simd.mul_f64s(
                    mj,
                    simd.add_f64s(simd.mul_f64s(cv, vj), simd.mul_f64s(ca, aj)),
                ),
            );
            let mut vnj = simd.div_f64s(rhs, simd.mul_f64s(mj, dscale));
            store::<S>(&mut vn[at.clone()], vnj);
            let end = range.start + j + w;
            let loads = rows.next_load < s.load_rows.len() && s.load_rows[rows.next_load] < end;
            let nodal = rows.next < rows.friction.len() && rows.friction[rows.next].0 < end;
            if loads || nodal {
                while rows.next_load < s.load_rows.len() && s.load_rows[rows.next_load] < end {
                    let i = s.load_rows[rows.next_load];
                    vn[i - r0] = s.rhs(i, ku[i - r0]) / (m[i - r0] * s.dscale);
                    rows.next_load += 1;
                }
                while rows.next < rows.friction.len() && rows.friction[rows.next].0 < end {
                    let (i, vi) = rows.friction[rows.next];
                    vn[i - r0] = vi;
                    rows.next += 1;
                }
                vnj = load::<S>(&vn[at.clone()]);
            }
            let anj = simd.sub_f64s(
                simd.mul_f64s(simd.sub_f64s(vnj, vj), scale),
                simd.mul_f64s(ratio, aj),
            );
            store::<S>(&mut an[at.clone()], anj);
            // predict's r + c1 ṙ + c2 r̈, for r_K, ṙ_K, r̈_K.
            let next = simd.add_f64s(
                simd.add_f64s(rnj, simd.mul_f64s(c1, vnj)),
                simd.mul_f64s(c2, anj),
            );
            store::<S>(&mut rx[at], next);
            finite = simd.add_f64s(
                finite,
                simd.add_f64s(simd.mul_f64s(rnj, zero), simd.mul_f64s(vnj, zero)),
            );
            strain[k] = simd.add_f64s(strain[k], simd.mul_f64s(rnj, kj));
            let mv = simd.mul_f64s(mj, vnj);
            kinetic[k] = simd.add_f64s(kinetic[k], simd.mul_f64s(mv, vnj));
        }
        (self.strain, self.kinetic, self.finite) = (strain, kinetic, finite);
    }

    /// The chunk's sums once every batch came: the held rows (fewer than
    /// a block, at the chunk's end) one row a time in their lanes, then
    /// [kinetic, not finite, strain].
    #[inline(always)]
    fn finish(mut self) -> [f64; 5] {
        if self.rows.s.damped.is_some() {
            return self.damped_sums;
        }
        let w = S::F64_LANES;
        let lanes = |v: &[S::f64s; LANES]| -> Lanes {
            let mut l = [0.0; LANES];
            for (k, v) in v.iter().take(LANES / w).enumerate() {
                store::<S>(&mut l[k * w..(k + 1) * w], *v);
            }
            Lanes(l)
        };
        let (mut strain, mut kinetic) = (lanes(&self.strain), lanes(&self.kinetic));
        let mut finite = self.simd.reduce_sum_f64s(self.finite) == 0.0;
        let held = self.held;
        if held > 0 {
            let rows = &mut self.rows;
            let s = rows.s;
            let r0 = rows.start + rows.vn.len() - held;
            for k in 0..held {
                let i = r0 + k;
                let ku = self.pending[k];
                let vi = rows.row(i, ku);
                finite &= s.r_new[i].is_finite() && vi.is_finite();
                strain.0[k] += s.r_new[i] * ku;
                kinetic.0[k] += s.mass[i] * vi * vi;
            }
        }
        [
            kinetic.total(),
            if finite { 0.0 } else { 1.0 },
            strain.total(),
            0.0,
            0.0,
        ]
    }

    /// A damped sweep's rows `r0..r0 + ku.len()`, one at a time (any
    /// range): what [`Aligned::rows`] and [`Aligned::finish`] do, with
    /// [`StepData::rhs`]'s damping force and m·dscale, K r_K kept, and the
    /// damping's sums.
    fn damped_rows(&mut self, r0: usize, ku: &[f64]) {
        let rows = &mut self.rows;
        let s = rows.s;
        let d = s.damped.as_ref().expect("a damped sweep");
        let sums = &mut self.damped_sums;
        let half_dt = 0.5 * s.next[0];
        for (j, &kui) in ku.iter().enumerate() {
            let i = r0 + j;
            let vi = rows.row(i, kui);
            if let Some(out) = rows.ku.as_deref_mut() {
                out[i - rows.start] = kui;
            }
            if !(s.r_new[i].is_finite() && vi.is_finite()) {
                sums[1] = 1.0;
            }
            sums[0] += s.mass[i] * vi * vi;
            sums[2] += s.r_new[i] * kui;
            let mean = 0.5 * (vi + s.v[i]);
            sums[3] += s.mass[i] * mean * mean;
            sums[4] += (kui - d.ku_prev[i]) * (s.v[i] + half_dt * s.a[i]);
        }
    }
}

impl<S: Simd> Batches for Aligned<'_, '_, S> {
    #[inline(always)]
    fn batch(&mut self, r0: usize, ku: &[f64]) {
        if self.rows.s.damped.is_some() {
            return self.damped_rows(r0, ku);
        }
        let (mut r, mut ku) = (r0, ku);
        if self.held > 0 {
            // Complete the held block from this batch's first rows.
            let take = (LANES - self.held).min(ku.len());
            self.pending[self.held..self.held + take].copy_from_slice(&ku[..take]);
            self.held += take;
            (r, ku) = (r + take, &ku[take..]);
            if self.held < LANES {
                return;
            }
            let block: [f64; LANES] = std::array::from_fn(|k| self.pending[k]);
            self.rows(r - LANES, &block);
            self.held = 0;
        }
        debug_assert_eq!((r - self.rows.start) % LANES, 0);
        let blocks = ku.len() / LANES * LANES;
        self.rows(r, &ku[..blocks]);
        let rest = &ku[blocks..];
        self.pending[..rest.len()].copy_from_slice(rest);
        self.held = rest.len();
    }
}
