//! The ordering of a sparse Cholesky factor: faer's AMD, a nested
//! dissection given by the caller (fem computes one from the mesh's
//! cells), or the dissection unless AMD's factor is clearly smaller,
//! decided at the first analysis ([`crate::analyze_symbolic`]) and shared
//! by every clone (the matrices of one model share one pattern).

use std::sync::{Arc, OnceLock};

/// The dissection is kept unless its factor has more than this many times
/// AMD's values: at about equal values its supernodes are larger and its
/// solves faster, and where AMD wins (non-convex domains, long thin
/// strips) it wins by more than this margin (docs/performance.md).
pub const AMD_MARGIN: f64 = 1.1;

/// The ordering the factorizations of a model's matrices use: faer's AMD,
/// a nested dissection, or the dissection unless AMD's factor is smaller
/// by [`AMD_MARGIN`], decided at the first analysis
/// ([`crate::analyze_symbolic`]) and shared by every clone.
#[derive(Clone, Debug, Default)]
pub struct FillOrder {
    /// The dissection's elimination order of the free DOFs, if a candidate.
    dissection: Option<Arc<Vec<usize>>>,
    /// Whether AMD is to be tried beside it.
    compare: bool,
    /// The comparison's outcome, once made: true when the dissection won.
    chosen: Arc<OnceLock<bool>>,
    /// The DOFs of the dissection's two first halves, which its order
    /// numbers first (the first half's, then the second's) and its first
    /// separator after them: a factorization may split there
    /// (`split.rs`).
    halves: Option<[usize; 2]>,
}

impl FillOrder {
    /// faer's AMD.
    pub fn amd() -> FillOrder {
        FillOrder::default()
    }

    /// The nested dissection `order`, whatever its factor.
    pub fn dissection(order: Vec<usize>) -> FillOrder {
        FillOrder {
            dissection: Some(Arc::new(order)),
            ..FillOrder::default()
        }
    }

    /// The nested dissection `order`, unless AMD's factor has fewer
    /// values by [`AMD_MARGIN`]: compared at the first analysis.
    pub fn dissection_unless_amd(order: Vec<usize>) -> FillOrder {
        FillOrder {
            compare: true,
            ..FillOrder::dissection(order)
        }
    }

    /// This order, its first `halves[0]` DOFs and the next `halves[1]`
    /// the dissection's two first halves, uncoupled in the matrices
    /// factorized (only the separator after them touches both).
    pub fn with_halves(self, halves: [usize; 2]) -> FillOrder {
        FillOrder {
            halves: Some(halves),
            ..self
        }
    }

    /// The dissection's two first halves ([`FillOrder::with_halves`]),
    /// where known and the dissection is the order (decided).
    pub fn halves(&self) -> Option<[usize; 2]> {
        let decided = !self.compare || self.chosen.get() == Some(&true);
        self.halves.filter(|_| self.dissection.is_some() && decided)
    }

    /// "AMD" or "nested dissection" (what the factors use, once decided),
    /// for messages.
    pub fn name(&self) -> &'static str {
        match (self.dissection.is_some(), self.compare, self.chosen.get()) {
            (false, _, _) | (true, true, Some(false)) => "AMD",
            (true, false, _) | (true, true, Some(true)) => "nested dissection",
            (true, true, None) => "nested dissection (or AMD, if its factor is clearly smaller)",
        }
    }

    /// [`FillOrder::name`] once the ordering is decided ("AMD" or "nested
    /// dissection"); `None` while the comparison with AMD waits for the
    /// first analysis.
    pub fn decided_name(&self) -> Option<&'static str> {
        let undecided = self.dissection.is_some() && self.compare && self.chosen.get().is_none();
        (!undecided).then(|| self.name())
    }

    /// Decides for the dissection where the comparison with AMD is still
    /// open, without AMD's analysis: for a run that factorizes once (the
    /// explicit scheme's preload) AMD's analysis costs about what its
    /// smaller factor saves where it wins, and all of it where it does
    /// not (docs/performance.md).
    pub fn keep_dissection(&self) {
        if let Some(chosen) = self.comparison() {
            let _ = chosen.set(true);
        }
    }

    /// The dissection's order, if it is a candidate.
    pub fn dissection_order(&self) -> Option<&[usize]> {
        self.dissection.as_deref().map(Vec::as_slice)
    }

    /// Where the comparison with AMD is kept, if the dissection is to be
    /// compared with AMD: empty until the first analysis, then true when
    /// the dissection won.
    pub(crate) fn comparison(&self) -> Option<&OnceLock<bool>> {
        (self.dissection.is_some() && self.compare).then_some(&*self.chosen)
    }
}
