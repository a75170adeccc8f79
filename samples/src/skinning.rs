//! GPU skinning, as an engine does it: each frame a compute pass bends every skinned mesh's
//! rest vertices by its joints' matrices (posed on the CPU: a few per mesh) into that frame
//! slot's vertex buffer, which the raster pass draws and the SDK refits the mesh's BLAS from
//! (`TaskOperation::Update` on an `allow_update` geometry). No vertex ever goes through the
//! CPU after loading.
use crate::gpu::{push_layout, shader_module, spirv, UploadSlots};
use crate::mesh_buffers::{interleave, Vertex, VERTEX_STRIDE};
use crate::scene::SampleScene;
use ash::vk;
use hybrid_rt_host::{Host, HostBuffer, HostResult};

/// A vertex's four joints and their weights (`Influence` in shaders/sample/skin.comp).
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct Influence {
    joints: [u32; 4],
    weights: [f32; 4],
}

#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct Push {
    vertex_count: u32,
    joint_offset: u32,
    joint_count: u32,
}

/// One skinned mesh's inputs on the GPU.
struct Skinned {
    mesh: usize,
    vertex_count: u32,
    rest: HostBuffer,
    influences: HostBuffer,
}

/// The skinning pipeline and the scene's skinned meshes.
pub struct SkinningPass {
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    push: ash::khr::push_descriptor::Device,
    meshes: Vec<Skinned>,
    /// The frame's joint matrices, all meshes' one after the other, per frame slot.
    joints: UploadSlots,
}

/// The usage of a posed vertex buffer: written by the pass, drawn, copied by the SDK.
pub const POSED_USAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::STORAGE_BUFFER.as_raw()
        | vk::BufferUsageFlags::VERTEX_BUFFER.as_raw()
        | vk::BufferUsageFlags::TRANSFER_SRC.as_raw(),
);

/// Mesh `k`'s vertices at rest, interleaved as the raster pass draws them.
pub fn rest_vertices(scene: &SampleScene, k: usize) -> Vec<Vertex> {
    interleave(&scene.scene.meshes[k].positions, scene.vertex_attributes(k))
}

impl SkinningPass {
    pub fn new(host: &Host, scene: &SampleScene) -> HostResult<SkinningPass> {
        let bindings: Vec<_> = (0..4)
            .map(|i| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i)
                    .descriptor_count(1)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let (set_layout, layout) =
            push_layout(host, &bindings, std::mem::size_of::<Push>() as u32, vk::ShaderStageFlags::COMPUTE)?;
        let module = shader_module(host, spirv::SKIN_COMP)?;
        let stage =
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::COMPUTE).module(module).name(c"main");
        // SAFETY: valid create info; the module is destroyed once the pipeline exists.
        let pipeline = unsafe {
            let p = host.device.create_compute_pipelines(
                vk::PipelineCache::null(),
                &[vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout)],
                None,
            );
            host.device.destroy_shader_module(module, None);
            p.map_err(|(_, e)| format!("skinning pipeline: {e:?}"))?[0]
        };
        let mut pass = SkinningPass {
            set_layout,
            layout,
            pipeline,
            push: ash::khr::push_descriptor::Device::new(&host.instance, &host.device),
            meshes: Vec::new(),
            joints: UploadSlots::new(vk::BufferUsageFlags::STORAGE_BUFFER),
        };
        for m in &scene.rig.skinned {
            let rest = rest_vertices(scene, m.mesh);
            let influences: Vec<Influence> = (0..rest.len())
                .map(|v| Influence {
                    joints: m.joints.get(v).copied().unwrap_or_default(),
                    weights: m.weights.get(v).copied().unwrap_or([1.0, 0.0, 0.0, 0.0]),
                })
                .collect();
            let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
            let rest_buffer = host.device_buffer_with_data(bytemuck::cast_slice(&rest), usage);
            let influence_buffer = host.device_buffer_with_data(bytemuck::cast_slice(&influences), usage);
            match (rest_buffer, influence_buffer) {
                (Ok(rest_buffer), Ok(influences)) => {
                    pass.meshes.push(Skinned { mesh: m.mesh, vertex_count: rest.len() as u32, rest: rest_buffer, influences })
                }
                (a, b) => {
                    let e = a.as_ref().err().or(b.as_ref().err()).cloned().unwrap_or_default();
                    for buffer in [a, b].into_iter().flatten() {
                        host.destroy_buffer(buffer);
                    }
                    pass.destroy(host);
                    return Err(e);
                }
            }
        }
        Ok(pass)
    }

    /// One frame slot's posed vertex buffers, one per skinned mesh (at rest until the first
    /// dispatch).
    pub fn posed_buffers(&self, host: &Host, scene: &SampleScene) -> HostResult<Vec<HostBuffer>> {
        let mut out = Vec::new();
        for m in &self.meshes {
            match host.device_buffer_with_data(bytemuck::cast_slice(&rest_vertices(scene, m.mesh)), POSED_USAGE) {
                Ok(b) => out.push(b),
                Err(e) => {
                    for b in out {
                        host.destroy_buffer(b);
                    }
                    return Err(e);
                }
            }
        }
        Ok(out)
    }

    /// Records the skinning of every skinned mesh, the rig's nodes at `pose`, into `posed` (this slot's
    /// buffers, as `posed_buffers` made them); returns (mesh, buffer) for each. The caller
    /// puts a barrier between these writes and the draws and BLAS refits that read them.
    pub fn record(
        &mut self,
        host: &Host,
        cmd: vk::CommandBuffer,
        slot: usize,
        scene: &SampleScene,
        pose: &[glam::Mat4],
        posed: &[HostBuffer],
    ) -> HostResult<Vec<(usize, vk::Buffer)>> {
        if self.meshes.is_empty() {
            return Ok(Vec::new());
        }
        let mut joints: Vec<glam::Mat4> = Vec::new();
        let mut offsets = Vec::new();
        for m in &scene.rig.skinned {
            offsets.push((joints.len() as u32, scene.rig.skins[m.skin].joints.len() as u32));
            joints.extend(scene.rig.joint_matrices(m.skin, pose));
        }
        let joint_buffer = self.joints.write(host, slot, bytemuck::cast_slice(&joints))?;
        let mut out = Vec::new();
        // SAFETY: cmd is recording; the buffers outlive the frame.
        unsafe {
            host.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline);
        }
        for ((m, &(joint_offset, joint_count)), target) in self.meshes.iter().zip(&offsets).zip(posed) {
            let infos = [m.rest.buffer, m.influences.buffer, joint_buffer, target.buffer]
                .map(|buffer| [vk::DescriptorBufferInfo { buffer, offset: 0, range: vk::WHOLE_SIZE }]);
            let writes: Vec<_> = infos
                .iter()
                .enumerate()
                .map(|(i, info)| {
                    vk::WriteDescriptorSet::default()
                        .dst_binding(i as u32)
                        .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                        .buffer_info(info)
                })
                .collect();
            let push = Push { vertex_count: m.vertex_count, joint_offset, joint_count };
            // SAFETY: cmd is recording, the pipeline bound above.
            unsafe {
                self.push.cmd_push_descriptor_set(cmd, vk::PipelineBindPoint::COMPUTE, self.layout, 0, &writes);
                host.device.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, bytemuck::bytes_of(&push));
                host.device.cmd_dispatch(cmd, m.vertex_count.div_ceil(64), 1, 1);
            }
            out.push((m.mesh, target.buffer));
        }
        Ok(out)
    }

    /// Bytes of a posed buffer (`VERTEX_STRIDE` per vertex).
    pub fn posed_bytes(&self, mesh: usize) -> Option<u64> {
        self.meshes.iter().find(|m| m.mesh == mesh).map(|m| m.vertex_count as u64 * VERTEX_STRIDE as u64)
    }

    pub fn destroy(self, host: &Host) {
        for m in self.meshes {
            host.destroy_buffer(m.rest);
            host.destroy_buffer(m.influences);
        }
        self.joints.destroy(host);
        // SAFETY: the caller waited for every frame that used the pass.
        unsafe {
            host.device.destroy_pipeline(self.pipeline, None);
            host.device.destroy_pipeline_layout(self.layout, None);
            host.device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
