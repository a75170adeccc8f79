//! The scene as the SDK sees it: Bevy's mesh entities mirrored as SDK geometries (one per mesh
//! asset) and instances (one per entity), kept in step through each frame's extraction.
use bevy::log::warn;
use bevy::platform::collections::{HashMap, HashSet};
use bevy::prelude::*;
use bevy::render::mesh::allocator::MeshAllocator;
use bevy::render::mesh::{RenderMesh, RenderMeshBufferInfo};
use bevy::render::render_asset::RenderAssets;
use bevy::render::sync_world::MainEntity;
use bevy::render::Extract;
use hybrid_rt::glam::{Affine3A, Mat3A, Vec3A};
use hybrid_rt::{
    GeometryHandle, GeometryInput, GeometryTask, IndexBufferInput, InstanceHandle, InstanceInput, InstanceOperation,
    InstanceTask, TaskContainer, TaskOperation, VertexBufferInput,
};
use hybrid_rt_wgpu::{wgpu, RtDevice};

/// This frame's visible mesh entities, from the main world.
#[derive(Resource, Default)]
pub(crate) struct ExtractedInstances(pub Vec<ExtractedInstance>);

/// A visible mesh entity: its mesh, placement and surface.
pub(crate) struct ExtractedInstance {
    entity: MainEntity,
    mesh: AssetId<Mesh>,
    transform: Affine3A,
    surface: Surface,
}

/// What the SDK's hit lighting shades a surface with: its diffuse albedo (linear, 0..=1) and
/// the light it emits (in the lit image's units).
#[derive(Clone, Copy, PartialEq, Debug)]
struct Surface {
    albedo: [f32; 3],
    emission: [f32; 3],
}

impl Surface {
    /// A `StandardMaterial`'s: its diffuse colour (base colour x (1 - metallic), as Bevy's
    /// lighting takes it); an unlit material shows its base colour as is, so it emits that.
    /// Lit materials' own emission comes from the cache (their lit image, injected). Without
    /// a `StandardMaterial`, the SDK's default grey.
    fn of(material: Option<&StandardMaterial>) -> Surface {
        let Some(m) = material else { return Surface { albedo: [0.5; 3], emission: [0.0; 3] } };
        let base = m.base_color.to_linear();
        let rgb = [base.red, base.green, base.blue].map(|c| c.clamp(0.0, 1.0));
        match m.unlit {
            true => Surface { albedo: [0.0; 3], emission: rgb },
            false => Surface { albedo: rgb.map(|c| c * (1.0 - m.metallic.clamp(0.0, 1.0))), emission: [0.0; 3] },
        }
    }
}

/// What `extract_instances` reads of a mesh entity.
type MeshEntity = (
    Entity,
    &'static Mesh3d,
    &'static GlobalTransform,
    &'static InheritedVisibility,
    Option<&'static MeshMaterial3d<StandardMaterial>>,
);

/// Render world, extraction: every entity with a mesh that is visible in the hierarchy.
/// (`InheritedVisibility`, not `ViewVisibility`: rays see what no camera frames.)
pub(crate) fn extract_instances(
    mut out: ResMut<ExtractedInstances>,
    query: Extract<Query<MeshEntity>>,
    materials: Extract<Res<Assets<StandardMaterial>>>,
) {
    out.0.clear();
    for (entity, mesh, transform, visible, material) in &query {
        if visible.get() {
            out.0.push(ExtractedInstance {
                entity: MainEntity::from(entity),
                mesh: mesh.id(),
                transform: to_sdk_affine(&transform.affine()),
                surface: Surface::of(material.and_then(|m| materials.get(&m.0))),
            });
        }
    }
}

/// Bevy's and the SDK's glam may be different versions: the affine by its columns.
fn to_sdk_affine(a: &bevy::math::Affine3A) -> Affine3A {
    let c = a.to_cols_array();
    Affine3A::from_mat3_translation(
        Mat3A::from_cols(Vec3A::new(c[0], c[1], c[2]), Vec3A::new(c[3], c[4], c[5]), Vec3A::new(c[6], c[7], c[8])).into(),
        Vec3A::new(c[9], c[10], c[11]).into(),
    )
}

/// Where a mesh's positions and indices live in Bevy's slabs, as last given to the SDK.
#[derive(Clone, Copy, PartialEq, Debug)]
struct MeshPlace {
    vertices: VertexBufferInput,
    indices: IndexBufferInput,
}

struct MirroredMesh {
    handle: GeometryHandle,
    place: MeshPlace,
}

struct MirroredInstance {
    handle: InstanceHandle,
    mesh: AssetId<Mesh>,
    transform: Affine3A,
    surface: Surface,
}

/// The SDK's handles for Bevy's meshes and entities.
#[derive(Default)]
pub(crate) struct SceneMirror {
    meshes: HashMap<AssetId<Mesh>, MirroredMesh>,
    instances: HashMap<MainEntity, MirroredInstance>,
    /// Meshes whose layout the SDK cannot read (no 32-bit float positions, not triangles),
    /// reported once.
    skipped: HashSet<AssetId<Mesh>>,
    /// Instances removed by this frame's container, freed once it is recorded.
    removed: Vec<InstanceHandle>,
    /// Geometries of meshes Bevy no longer has, freed with them.
    removed_meshes: Vec<GeometryHandle>,
}

/// What a frame's sync scheduled: whether anything changed, and the buffers the SDK copies
/// geometry from (they must be in the copy state when its commands run).
pub(crate) struct SyncOutcome {
    pub changed: bool,
    pub copies: Vec<wgpu::Buffer>,
}

impl SceneMirror {
    /// Schedules the geometry and instance tasks that bring the SDK's scene to this frame's
    /// entities: new meshes registered (or re-registered where Bevy's allocator moved them),
    /// new entities placed, moved ones updated, vanished ones removed and their handles freed.
    pub(crate) fn sync(
        &mut self,
        rt: &RtDevice,
        tasks: &mut TaskContainer,
        extracted: &ExtractedInstances,
        allocator: &MeshAllocator,
        meshes: &RenderAssets<RenderMesh>,
    ) -> std::result::Result<SyncOutcome, hybrid_rt_wgpu::BridgeError> {
        let ctx = rt.context();
        let mut out = SyncOutcome { changed: false, copies: Vec::new() };
        let mut seen = HashSet::new();
        let used: HashSet<AssetId<Mesh>> = extracted.0.iter().map(|i| i.mesh).collect();
        for ExtractedInstance { entity, mesh: mesh_id, transform, surface } in &extracted.0 {
            let Some(place) = self.place_of(rt, mesh_id, allocator, meshes, &mut out.copies)? else { continue };
            let geometry = match self.meshes.get_mut(mesh_id) {
                Some(m) if m.place == place => m.handle,
                Some(m) => {
                    // Bevy's allocator moved the mesh (a slab grew): the SDK copies it again.
                    m.place = place;
                    let input = geometry_input(place);
                    // SAFETY: Bevy's slab buffers live until the ticket returns (the plugin
                    // holds a clone of each buffer it names until then).
                    unsafe {
                        tasks.schedule_geometry(&GeometryTask { handle: m.handle, operation: TaskOperation::Update, input })
                    }?;
                    out.changed = true;
                    m.handle
                }
                None => {
                    let handle = ctx.create_geometry_handle();
                    // SAFETY: as above.
                    unsafe {
                        tasks.schedule_geometry(&GeometryTask { handle, input: geometry_input(place), ..Default::default() })
                    }?;
                    self.meshes.insert(*mesh_id, MirroredMesh { handle, place });
                    out.changed = true;
                    handle
                }
            };
            seen.insert(*entity);
            let input = InstanceInput {
                geometry,
                transform: *transform,
                albedo: surface.albedo,
                emission: surface.emission,
                ..Default::default()
            };
            let mirrored =
                MirroredInstance { handle: InstanceHandle::NULL, mesh: *mesh_id, transform: *transform, surface: *surface };
            match self.instances.get_mut(entity) {
                Some(i) if i.mesh == *mesh_id && i.transform == *transform && i.surface == *surface => {}
                Some(i) => {
                    tasks.schedule_instance(&InstanceTask { handle: i.handle, operation: InstanceOperation::Update, input })?;
                    *i = MirroredInstance { handle: i.handle, ..mirrored };
                    out.changed = true;
                }
                None => {
                    let handle = ctx.create_instance_handle();
                    tasks.schedule_instance(&InstanceTask { handle, input, ..Default::default() })?;
                    self.instances.insert(*entity, MirroredInstance { handle, ..mirrored });
                    out.changed = true;
                }
            }
        }
        // Meshes Bevy unloaded (no instance of this frame uses them): their geometries go once
        // the instances that used them are out (after this container is recorded).
        let unloaded: Vec<AssetId<Mesh>> =
            self.meshes.keys().filter(|id| meshes.get(**id).is_none() && !used.contains(*id)).copied().collect();
        for id in unloaded {
            if let Some(m) = self.meshes.remove(&id) {
                self.removed_meshes.push(m.handle);
            }
        }
        // Entities despawned, hidden or without their mesh any more: out of the TLAS, their
        // handles freed (the SDK frees GPU memory once the tickets in flight are back).
        let gone: Vec<MainEntity> = self.instances.keys().filter(|e| !seen.contains(*e)).copied().collect();
        for entity in gone {
            if let Some(i) = self.instances.remove(&entity) {
                tasks.schedule_instance(&InstanceTask {
                    handle: i.handle,
                    operation: InstanceOperation::Remove,
                    input: InstanceInput::default(),
                })?;
                self.removed.push(i.handle);
                out.changed = true;
            }
        }
        Ok(out)
    }

    /// Frees the handles of the instances the recorded container removed, then the geometries
    /// of unloaded meshes. (A handle must outlive the container that names it; the SDK frees
    /// GPU memory once the tickets in flight are back.)
    pub(crate) fn release_removed(&mut self, rt: &RtDevice) {
        if !self.removed.is_empty() {
            if let Err(e) = rt.context().destroy_instance_handles(&self.removed) {
                warn!("hybrid-rt: {e}");
            }
            self.removed.clear();
        }
        if !self.removed_meshes.is_empty() {
            if let Err(e) = rt.context().destroy_geometry_handles(&self.removed_meshes) {
                warn!("hybrid-rt: {e}");
            }
            self.removed_meshes.clear();
        }
    }

    /// Where a mesh lives in Bevy's slabs, or None (not uploaded yet, or not readable by the SDK).
    fn place_of(
        &mut self,
        rt: &RtDevice,
        mesh_id: &AssetId<Mesh>,
        allocator: &MeshAllocator,
        meshes: &RenderAssets<RenderMesh>,
        copies: &mut Vec<wgpu::Buffer>,
    ) -> std::result::Result<Option<MeshPlace>, hybrid_rt_wgpu::BridgeError> {
        let (Some(mesh), Some(vertices)) = (meshes.get(*mesh_id), allocator.mesh_vertex_slice(mesh_id)) else {
            return Ok(None);
        };
        let layout = mesh.layout.0.layout();
        let position =
            mesh.layout.0.attribute_ids().iter().position(|id| *id == Mesh::ATTRIBUTE_POSITION.id).map(|k| layout.attributes[k]);
        let readable = mesh.key_bits.primitive_topology() == bevy::mesh::PrimitiveTopology::TriangleList
            && position.is_some_and(|p| p.format == wgpu::VertexFormat::Float32x3);
        if !readable {
            if self.skipped.insert(*mesh_id) {
                warn!("hybrid-rt: mesh {mesh_id:?} is not a triangle list with Float32x3 positions; rays do not see it");
            }
            return Ok(None);
        }
        let stride = layout.array_stride;
        let position_offset = position.map_or(0, |p| p.offset);
        let vertex_buffer: &wgpu::Buffer = vertices.buffer;
        let mut place = MeshPlace {
            vertices: VertexBufferInput {
                buffer: rt.buffer(vertex_buffer)?,
                offset: vertices.range.start as u64 * stride + position_offset,
                stride,
                count: vertices.range.end - vertices.range.start,
                ..Default::default()
            },
            indices: IndexBufferInput::default(),
        };
        push_unique(copies, vertex_buffer);
        if let RenderMeshBufferInfo::Indexed { count, index_format } = mesh.buffer_info {
            let Some(indices) = allocator.mesh_index_slice(mesh_id) else { return Ok(None) };
            let (size, format) = match index_format {
                wgpu::IndexFormat::Uint16 => (2, ash::vk::Format::R16_UINT),
                wgpu::IndexFormat::Uint32 => (4, ash::vk::Format::R32_UINT),
            };
            let index_buffer: &wgpu::Buffer = indices.buffer;
            place.indices =
                IndexBufferInput { buffer: rt.buffer(index_buffer)?, offset: indices.range.start as u64 * size, count, format };
            push_unique(copies, index_buffer);
        }
        Ok(Some(place))
    }
}

fn push_unique(list: &mut Vec<wgpu::Buffer>, buffer: &wgpu::Buffer) {
    if !list.iter().any(|b| b == buffer) {
        list.push(buffer.clone());
    }
}

fn geometry_input(place: MeshPlace) -> GeometryInput {
    GeometryInput { vertices: place.vertices, indices: place.indices, ..Default::default() }
}
