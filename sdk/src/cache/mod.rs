//! The surfel direct-lighting cache: per-geometry layouts (built on the CPU from a read-back
//! copy of the geometry), per-instance sample ranges in large shared pages, and the instance
//! table that lets shaders find both by buffer device address.
pub(crate) mod layout;
pub(crate) mod pool;
pub(crate) mod table;
