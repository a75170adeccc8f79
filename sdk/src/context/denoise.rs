//! Denoising contexts: created and destroyed by the engine, their history images owned here
//! and freed only after the tickets that could still use them come back.
use super::{ExecuteContext, Shared};
use crate::error::{Error, Result};
use crate::gpu::deferred::Garbage;
use crate::passes::denoise::DenoiserState;
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
        let state = DenoiserState::new(&self.shared.memory, input)?;
        let mut st = self.shared.state.lock();
        // The shared intermediates grow to this context's size; on failure nothing changes.
        let replaced = match st.denoise_temps.ensure(&self.shared.memory, input) {
            Ok(r) => r,
            Err(e) => {
                for image in state.into_images() {
                    self.shared.memory.destroy_image(image);
                }
                return Err(e);
            }
        };
        let serial = st.last_issued();
        for image in replaced {
            st.deferred.retire(serial, Garbage::Image(image));
        }
        let h = st.denoisers.insert(state);
        self.shared.live.write().denoisers.insert(h.0);
        Ok(h)
    }

    /// Destroys a denoising context. Tasks still scheduled with it fail at build; its images
    /// (and, with the last context, the shared intermediates) are freed once the tickets
    /// issued so far have come back.
    pub fn destroy_denoising_context(&self, handle: DenoisingContextHandle) -> Result<()> {
        let mut st = self.shared.state.lock();
        let state = st.denoisers.remove(handle)?;
        self.shared.live.write().denoisers.remove(&handle.0);
        let serial = st.last_issued();
        for image in state.into_images() {
            st.deferred.retire(serial, Garbage::Image(image));
        }
        // The last context takes the shared intermediates with it.
        if st.denoisers.iter().next().is_none() {
            for image in std::mem::take(&mut st.denoise_temps).into_images() {
                st.deferred.retire(serial, Garbage::Image(image));
            }
        }
        Ok(())
    }
}

impl Shared {
    pub(crate) fn check_denoising_context_alive(&self, h: DenoisingContextHandle) -> Result<()> {
        if self.live.read().denoisers.contains(&h.0) {
            return Ok(());
        }
        Err(super::handles::not_live(DenoisingContextHandle::KIND, h.0, self.id))
    }
}
