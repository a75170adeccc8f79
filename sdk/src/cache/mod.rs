//! The surfel direct-lighting cache: per-geometry layouts (built on the CPU from a read-back
//! copy of the geometry) and per-instance sample ranges in large shared pages. Shaders find
//! both through the scene's instance table (`scene::table`).
pub(crate) mod layout;
pub(crate) mod pool;
