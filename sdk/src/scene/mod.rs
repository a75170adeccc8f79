//! Scene state: geometry and instance registries, the BLAS build queue with its throttle,
//! BLAS compaction, and the TLAS snapshot that working sets build from.
pub(crate) mod blas;
pub(crate) mod geometry;
pub(crate) mod instance;
pub(crate) mod tlas;
