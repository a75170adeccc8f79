//! Denoising contexts: created and destroyed by the engine, their history images owned here
//! and freed only after the tickets that could still use them come back.
use super::{ExecuteContext, Shared};
use crate::error::{Error, Result};
use crate::gpu::deferred::Garbage;
use crate::passes::denoise::DenoiserState;
use crate::types::DenoisingContextHandle;
use crate::types::{DenoiseJob, DenoisingContextInput};

use crate::types::MAX_DENOISING_EXTENT;

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
        }
        let state = DenoiserState::new(&self.shared.memory, input)?;
        Ok(self.shared.state.lock().denoisers.insert(state))
    }

    /// Destroys a denoising context. Tasks still scheduled with it fail at build; its images
    /// are freed once the tickets issued so far have come back.
    pub fn destroy_denoising_context(&self, handle: DenoisingContextHandle) -> Result<()> {
        let mut st = self.shared.state.lock();
        let state = st.denoisers.remove(handle)?;
        let serial = st.last_issued();
        for image in state.into_images() {
            st.deferred.retire(serial, Garbage::Image(image));
        }
        Ok(())
    }
}

impl Shared {
    pub(crate) fn check_denoising_context_alive(&self, h: DenoisingContextHandle) -> Result<()> {
        self.state.lock().denoisers.check(h).map(|_| ())
    }
}

/// At build: the context still exists, denoises this task's signal and is large enough.
pub(super) fn check_job(
    denoisers: &crate::types::handles::Registry<DenoisingContextHandle, DenoiserState>,
    job: &DenoiseJob,
) -> Result<()> {
    let state = denoisers.get(job.context)?;
    if state.input.signal != job.signal {
        return Err(Error::invalid(
            "denoise task context",
            format!("the context denoises {:?}, the task is {:?}", state.input.signal, job.signal),
        ));
    }
    // History is kept at the pixels' own coordinates: the viewport's far corner must fit.
    let vp = &job.common.viewport;
    let (right, bottom) = (vp.x as u64 + vp.width as u64, vp.y as u64 + vp.height as u64);
    if right > state.input.max_width as u64 || bottom > state.input.max_height as u64 {
        return Err(Error::invalid(
            "denoise task viewport",
            format!("reaches ({right}, {bottom}), beyond the context's {}x{}", state.input.max_width, state.input.max_height),
        ));
    }
    Ok(())
}
