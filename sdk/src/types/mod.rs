//! The public plain data: what an engine fills in and gets back. Task structs by family, handles,
//! settings, tickets and limits — `Default` everywhere, no Vulkan calls. The C ABI mirrors these
//! structs field for field. Everything here is re-exported at the crate root.
pub mod cache;
pub mod denoise;
pub mod handles;
pub mod inputs;
pub mod limits;
pub mod many_lights;
pub mod scene;
pub mod settings;
pub mod ticket;
pub mod trace;

pub use cache::*;
pub use denoise::*;
pub use handles::{DenoisingContextHandle, GeometryHandle, InstanceHandle, ManyLightsContextHandle};
pub use inputs::*;
pub use limits::*;
pub use many_lights::*;
pub use scene::*;
pub use settings::*;
pub use ticket::*;
pub use trace::*;
