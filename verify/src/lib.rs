//! The solver's proof of itself: closed-form checks, convergence rates, the
//! paper's experiments, committed reference runs, and the paper's figures.
