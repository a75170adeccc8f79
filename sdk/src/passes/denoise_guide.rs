//! The denoiser's guide: the G-buffer its passes test edges and disocclusion against (an
//! octahedral normal and the view distance per pixel, written by each task's first pass from
//! the engine's depth and normals), this frame's and the last.
//!
//! NRD keeps the previous frame's depth and normals once per denoiser instance; we keep them
//! once per camera view. Contexts created with the same `DenoisingContextInput::view_id`
//! share one guide (the sample's four contexts of the main camera kept four copies of the
//! same 8 bytes per pixel), so a view's first denoise task of a recording moves the guide to
//! a new frame and its later tasks rewrite the same texels. A context with view id 0 keeps a
//! guide of its own, which moves with every task, as before views existed.
use crate::error::{Error, Result};
use crate::gpu::memory::{Image, Memory, MemoryKind};
use crate::types::{DenoisingCommon, DenoisingContextHandle};
use ash::vk;

/// Packed normal (two signed bytes) + view distance (a half), one 32-bit texel.
const GUIDE_FORMAT: vk::Format = vk::Format::R32_UINT;

/// Which guide a context reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum GuideKey {
    /// A context's own (view id 0).
    Context(u64),
    /// A view's, shared by its contexts.
    View(u32),
}

impl GuideKey {
    /// The guide of a context of `view_id` (`handle`: the context's).
    pub fn of(view_id: u32, handle: DenoisingContextHandle) -> GuideKey {
        if view_id == 0 {
            GuideKey::Context(handle.0)
        } else {
            GuideKey::View(view_id)
        }
    }
}

/// One view's guide: a ping-pong pair of images and the frame count that tells a context
/// whether its history continues from the guide's previous frame.
pub(crate) struct Guide {
    images: [Image; 2],
    /// The image the latest frame went into.
    newest: usize,
    /// Frames begun so far.
    frame: u64,
    /// The recording (ticket serial) that began the latest frame.
    recorded: Option<u64>,
    /// Whether its images have left UNDEFINED.
    pub initialized: bool,
    pub width: u32,
    pub height: u32,
    /// Contexts reading it: the last one destroyed takes it along.
    pub users: u32,
}

impl Guide {
    pub fn new(memory: &Memory, width: u32, height: u32) -> Result<Guide> {
        let first = memory.create_image("denoiser guide", GUIDE_FORMAT, width, height, MemoryKind::Denoiser)?;
        let second = match memory.create_image("denoiser guide", GUIDE_FORMAT, width, height, MemoryKind::Denoiser) {
            Ok(i) => i,
            Err(e) => {
                memory.destroy_image(first);
                return Err(e);
            }
        };
        Ok(Guide { images: [first, second], newest: 0, frame: 0, recorded: None, initialized: false, width, height, users: 0 })
    }

    pub fn images(&self) -> &[Image; 2] {
        &self.images
    }

    pub fn into_images(self) -> [Image; 2] {
        self.images
    }

    /// Begins a task of the recording `serial`: a context's own guide, and a view's on its first
    /// task of the recording, move to a new frame. Returns the frame the task writes and
    /// (previous, current) image indices.
    pub fn begin_task(&mut self, serial: u64, shared: bool) -> (u64, [usize; 2]) {
        if !shared || self.recorded != Some(serial) {
            self.newest = 1 - self.newest;
            self.frame += 1;
            self.recorded = Some(serial);
        }
        (self.frame, [1 - self.newest, self.newest])
    }

    /// The bookkeeping a task advances, for the state digest.
    #[cfg(feature = "fault-injection")]
    pub fn digest(&self) -> String {
        format!("newest {} frame {} recorded {:?} users {}", self.newest, self.frame, self.recorded, self.users)
    }
}

/// What the denoise tasks of one view in one recording must agree on: they share the guide,
/// which each of them writes from these inputs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ViewInputs {
    depth: vk::ImageView,
    normals: vk::ImageView,
    input_mask: vk::ImageView,
    viewport: [u32; 4],
    camera: [[f32; 16]; 2],
}

impl ViewInputs {
    pub fn of(c: &DenoisingCommon) -> ViewInputs {
        ViewInputs {
            depth: c.depth.image.view,
            normals: c.normals.image.view,
            input_mask: c.input_mask.view,
            viewport: [c.viewport.x, c.viewport.y, c.viewport.width, c.viewport.height],
            camera: [c.camera.world_to_view.to_cols_array(), c.camera.view_to_clip.to_cols_array()],
        }
    }

    /// Checks `self` against the inputs an earlier task of view `view_id` in the same build
    /// recorded in `seen` (or records them).
    pub fn check(self, view_id: u32, seen: &mut Vec<(u32, ViewInputs)>) -> Result<()> {
        match seen.iter().find(|(v, _)| *v == view_id) {
            Some((_, earlier)) if *earlier != self => Err(Error::invalid(
                "DenoisingContextInput.view_id",
                format!(
                    "two denoise tasks of view {view_id} in one container differ in depth, normals, input mask, \
                     viewport or camera: the contexts of one view denoise one camera's G-buffer (give each camera \
                     its own view id)"
                ),
            )),
            Some(_) => Ok(()),
            None => {
                seen.push((view_id, self));
                Ok(())
            }
        }
    }
}
