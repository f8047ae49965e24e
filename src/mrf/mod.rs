//! General discrete MRF solvers, kept apart from the models that use them (the soup builds its
//! energies; these only minimise them):
//! - [`graphcut`]: α-expansion with Potts smoothness and label costs (max-flow moves), used by
//!   the motion assignment of the unit-scale soup;
//! - [`trws`]: sequential tree-reweighted message passing (TRW-S) for arbitrary pairwise tables,
//!   used by the particle refinement of the soup.

pub mod graphcut;
pub mod trws;
