//! GPU skinning, as an engine does it: each frame a compute pass displaces every deforming
//! mesh's rest vertices by its morph targets (weights from the CPU: a few per mesh) and bends
//! them by its joints' matrices (posed on the CPU: a few per mesh) into that frame slot's
//! vertex buffer, which the raster pass draws and the SDK refits the mesh's BLAS from
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
    target_count: u32,
    weight_offset: u32,
}

/// One deforming mesh's inputs on the GPU.
struct Skinned {
    mesh: usize,
    vertex_count: u32,
    target_count: u32,
    rest: HostBuffer,
    influences: HostBuffer,
    /// Per target, per vertex: position, normal and tangent displacements (xyz of three
    /// vec4s; a placeholder vec4 for a mesh without targets).
    displacements: HostBuffer,
}

/// A mesh's morph-target displacements as skin.comp reads them (target-major).
fn displacements(morph: Option<&crate::skin::Morph>, vertices: usize) -> Vec<[f32; 4]> {
    let Some(morph) = morph else { return vec![[0.0; 4]] };
    let mut out = Vec::with_capacity(morph.targets.len() * vertices * 3);
    for t in &morph.targets {
        for v in 0..vertices {
            for list in [&t.positions, &t.normals, &t.tangents] {
                out.push(list.get(v).map_or([0.0; 4], |d| d.extend(0.0).to_array()));
            }
        }
    }
    if out.is_empty() {
        out.push([0.0; 4]);
    }
    out
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
    /// The frame's morph-target weights, all meshes' one after the other, per frame slot.
    weights: UploadSlots,
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
        let bindings: Vec<_> = (0..6)
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
            weights: UploadSlots::new(vk::BufferUsageFlags::STORAGE_BUFFER),
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
            let moves = displacements(m.morph.as_ref(), rest.len());
            let buffers = [bytemuck::cast_slice(&rest), bytemuck::cast_slice(&influences), bytemuck::cast_slice(&moves)]
                .map(|bytes| host.device_buffer_with_data(bytes, usage));
            match buffers {
                [Ok(rest_buffer), Ok(influences), Ok(displacements)] => pass.meshes.push(Skinned {
                    mesh: m.mesh,
                    vertex_count: rest.len() as u32,
                    target_count: m.morph.as_ref().map_or(0, |k| k.targets.len() as u32),
                    rest: rest_buffer,
                    influences,
                    displacements,
                }),
                made => {
                    let e = made.iter().find_map(|b| b.as_ref().err()).cloned().unwrap_or_default();
                    for buffer in made.into_iter().flatten() {
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

    /// Records the deformation of every deforming mesh at `time`, the rig's nodes at `pose`,
    /// into `posed` (this slot's buffers, as `posed_buffers` made them); returns (mesh, buffer)
    /// for each. The caller puts a barrier between these writes and the draws and BLAS refits
    /// that read them.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        host: &Host,
        cmd: vk::CommandBuffer,
        slot: usize,
        scene: &SampleScene,
        time: f32,
        pose: &[glam::Mat4],
        posed: &[HostBuffer],
    ) -> HostResult<Vec<(usize, vk::Buffer)>> {
        if self.meshes.is_empty() {
            return Ok(Vec::new());
        }
        // (A mesh without a skin has no joints: the shader's missing joints are identities.)
        let mut joints: Vec<glam::Mat4> = vec![glam::Mat4::IDENTITY];
        let mut weights: Vec<f32> = vec![0.0];
        let mut offsets = Vec::new();
        for m in &scene.rig.skinned {
            let skin = m.skin.map_or(0, |k| scene.rig.skins[k].joints.len() as u32);
            offsets.push((joints.len() as u32, skin, weights.len() as u32));
            if let Some(k) = m.skin {
                joints.extend(scene.rig.joint_matrices(k, pose));
            }
            if let Some(morph) = &m.morph {
                weights.extend(scene.rig.morph_weights(morph, time));
            }
        }
        let joint_buffer = self.joints.write(host, slot, bytemuck::cast_slice(&joints))?;
        let weight_buffer = self.weights.write(host, slot, bytemuck::cast_slice(&weights))?;
        let mut out = Vec::new();
        // SAFETY: cmd is recording; the buffers outlive the frame.
        unsafe {
            host.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline);
        }
        for ((m, &(joint_offset, joint_count, weight_offset)), target) in self.meshes.iter().zip(&offsets).zip(posed) {
            let buffers =
                [m.rest.buffer, m.influences.buffer, joint_buffer, target.buffer, m.displacements.buffer, weight_buffer];
            let infos = buffers.map(|buffer| [vk::DescriptorBufferInfo { buffer, offset: 0, range: vk::WHOLE_SIZE }]);
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
            let push =
                Push { vertex_count: m.vertex_count, joint_offset, joint_count, target_count: m.target_count, weight_offset };
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
            host.destroy_buffer(m.displacements);
        }
        self.joints.destroy(host);
        self.weights.destroy(host);
        // SAFETY: the caller waited for every frame that used the pass.
        unsafe {
            host.device.destroy_pipeline(self.pipeline, None);
            host.device.destroy_pipeline_layout(self.layout, None);
            host.device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
