//! Many-lights contexts: created and destroyed by the engine, their light lists and resampling
//! history owned here and freed only after the tickets that could still use them come back.
use super::{ExecuteContext, Shared};
use crate::error::{Error, Result};
use crate::gpu::deferred::Garbage;
use crate::passes::many_lights::ManyLightsState;
use crate::types::{ManyLightsContextHandle, ManyLightsContextInput, MAX_MANY_LIGHTS, MAX_MANY_LIGHTS_EXTENT};

impl ExecuteContext {
    /// Creates a many-lights context for one view (see `ManyLightsContextInput`) and allocates
    /// its light list and history: 72 bytes a light and 40 bytes a pixel (a 1920x1080 view
    /// with 65,536 lights: 88 MB). Memory shows under `ResourceAllocations::many_lights`.
    pub fn create_many_lights_context(&self, input: &ManyLightsContextInput) -> Result<ManyLightsContextHandle> {
        for (what, v) in
            [("ManyLightsContextInput.max_width", input.max_width), ("ManyLightsContextInput.max_height", input.max_height)]
        {
            if !(1..=MAX_MANY_LIGHTS_EXTENT).contains(&v) {
                return Err(Error::invalid(what, format!("{v} is not in 1..={MAX_MANY_LIGHTS_EXTENT}")));
            }
        }
        if !(1..=MAX_MANY_LIGHTS).contains(&input.max_lights) {
            return Err(Error::invalid(
                "ManyLightsContextInput.max_lights",
                format!("{} is not in 1..={MAX_MANY_LIGHTS}", input.max_lights),
            ));
        }
        let state = ManyLightsState::new(&self.shared.memory, input)?;
        let mut st = self.shared.state.lock();
        let h = st.many_lights.insert(state);
        self.shared.live.write().many_lights.insert(h.0);
        Ok(h)
    }

    /// Destroys a many-lights context. Tasks still scheduled with it fail at build; its buffers
    /// are freed once the tickets issued so far have come back.
    pub fn destroy_many_lights_context(&self, handle: ManyLightsContextHandle) -> Result<()> {
        let mut st = self.shared.state.lock();
        let state = st.many_lights.remove(handle).map_err(|e| e.for_field("destroy_many_lights_context handle"))?;
        self.shared.live.write().many_lights.remove(&handle.0);
        let serial = st.last_issued();
        for buffer in state.into_buffers() {
            st.deferred.retire(serial, Garbage::Buffer(buffer));
        }
        Ok(())
    }
}

impl Shared {
    /// `h` is a live many-lights context; `field` names where the engine put it.
    pub(crate) fn check_many_lights_context_alive(&self, h: ManyLightsContextHandle, field: &'static str) -> Result<()> {
        if self.live.read().many_lights.contains(&h.0) {
            return Ok(());
        }
        Err(super::handles::not_live(field, ManyLightsContextHandle::KIND, h.0, self.id))
    }
}
