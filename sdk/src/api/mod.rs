//! What users touch: the context, task containers, handles, task structs and tickets.
pub mod container;
pub mod context;
pub mod denoising;
pub mod handles;
pub mod settings;
pub mod tasks;
pub mod ticket;
pub(crate) mod validate;
