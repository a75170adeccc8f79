//! Denoising contexts: created and destroyed by the engine, their history images (and their
//! views' guides) owned here and freed only after the tickets that could still use them come
//! back.
use super::{ExecuteContext, Shared};
use crate::error::{Error, Result};
use crate::gpu::deferred::Garbage;
use crate::passes::denoise::DenoiserState;
use crate::passes::denoise_guide::{Guide, GuideKey};
use crate::types::{DenoisingContextHandle, DenoisingContextInput, MAX_DENOISING_EXTENT};

impl ExecuteContext {
    /// Creates a denoising context and allocates its history (see `DenoisingContextInput`).
    /// Memory shows under `ResourceAllocations::denoiser`.
    pub fn create_denoising_context(&self, input: &DenoisingContextInput) -> Result<DenoisingContextHandle> {
        for (what, v) in
            [("DenoisingContextInput.max_width", input.max_width), ("DenoisingContextInput.max_height", input.max_height)]
        {
            if !(1..=MAX_DENOISING_EXTENT).contains(&v) {
                return Err(Error::invalid(what, format!("{v} is not in 1..={MAX_DENOISING_EXTENT}")));
            }
            let device_max = self.shared.device.limits.max_image_dimension_2d;
            if v > device_max {
                return Err(Error::invalid(what, format!("{v} exceeds the device's maxImageDimension2D {device_max}")));
            }
        }
        let memory = &self.shared.memory;
        let view = (input.view_id != 0).then_some(GuideKey::View(input.view_id));
        // Allocated before the lock, under a placeholder key (set once the handle exists).
        let state = DenoiserState::new(memory, input, GuideKey::Context(0))?;
        let mut st = self.shared.state.lock();
        let free = |state: DenoiserState, guide: Option<Guide>| {
            for image in state.into_images().into_iter().chain(guide.into_iter().flat_map(Guide::into_images)) {
                memory.destroy_image(image);
            }
        };
        // A view's contexts share its guide, so its size.
        let shared = view.and_then(|k| st.denoise_guides.get(&k));
        if let Some(g) = shared {
            if (g.width, g.height) != (input.max_width, input.max_height) {
                free(state, None);
                return Err(Error::invalid(
                    "DenoisingContextInput.view_id",
                    format!(
                        "view {}'s contexts are {}x{}, this one is {}x{}: one view's contexts have one size",
                        input.view_id, g.width, g.height, input.max_width, input.max_height
                    ),
                ));
            }
        }
        let new_guide = match shared {
            Some(_) => None,
            None => match Guide::new(memory, input.max_width, input.max_height) {
                Ok(g) => Some(g),
                Err(e) => {
                    free(state, None);
                    return Err(e);
                }
            },
        };
        // The shared intermediates grow to this context's size; on failure nothing changes.
        let replaced = match st.denoise_temps.ensure(memory, input) {
            Ok(r) => r,
            Err(e) => {
                free(state, new_guide);
                return Err(e);
            }
        };
        let serial = st.last_issued();
        for image in replaced {
            st.deferred.retire(serial, Garbage::Image(image));
        }
        let h = st.denoisers.insert(state);
        let key = GuideKey::of(input.view_id, h);
        if let Ok(state) = st.denoisers.get_mut(h) {
            state.guide = key;
        }
        if let Some(g) = new_guide {
            st.denoise_guides.insert(key, g);
        }
        // The view's guide, made above or found under the same lock.
        if let Some(guide) = st.denoise_guides.get_mut(&key) {
            guide.users += 1;
        }
        self.shared.live.write().denoisers.insert(h.0);
        Ok(h)
    }

    /// Destroys a denoising context. Tasks still scheduled with it fail at build; its images
    /// (and, with the last context, the shared intermediates) are freed once the tickets
    /// issued so far have come back.
    pub fn destroy_denoising_context(&self, handle: DenoisingContextHandle) -> Result<()> {
        let mut st = self.shared.state.lock();
        let state = st.denoisers.remove(handle).map_err(|e| e.for_field("destroy_denoising_context handle"))?;
        self.shared.live.write().denoisers.remove(&handle.0);
        let serial = st.last_issued();
        let key = state.guide;
        for image in state.into_images() {
            st.deferred.retire(serial, Garbage::Image(image));
        }
        // The last context of a view takes the view's guide with it.
        if let Some(guide) = st.denoise_guides.get_mut(&key) {
            guide.users -= 1;
            if guide.users == 0 {
                for image in st.denoise_guides.remove(&key).into_iter().flat_map(Guide::into_images) {
                    st.deferred.retire(serial, Garbage::Image(image));
                }
            }
        }
        // The last context takes the shared intermediates with it.
        if st.denoisers.iter().next().is_none() {
            for image in std::mem::take(&mut st.denoise_temps).into_images() {
                st.deferred.retire(serial, Garbage::Image(image));
            }
        }
        Ok(())
    }

    /// Destroys every denoising context (its history is freed once the tickets issued before
    /// are back, as for one). Tasks already scheduled with them fail at `build_gpu_task`.
    /// Kickstart RT's `DestroyAllDenoisingContextHandles`.
    pub fn destroy_all_denoising_context_handles(&self) {
        let all: Vec<DenoisingContextHandle> = self.shared.state.lock().denoisers.iter().map(|(h, _)| h).collect();
        for h in all {
            // Only a context another thread destroyed meanwhile fails here: gone either way.
            let _ = self.destroy_denoising_context(h);
        }
    }
}

impl Shared {
    /// `h` is a live denoising context; `field` names where the engine put it.
    pub(crate) fn check_denoising_context_alive(&self, h: DenoisingContextHandle, field: &'static str) -> Result<()> {
        if self.live.read().denoisers.contains(&h.0) {
            return Ok(());
        }
        Err(super::handles::not_live(field, DenoisingContextHandle::KIND, h.0, self.id))
    }
}
