//! Property-based tests of the entry points' input checks: a valid task, then one to four of its
//! fields set to hostile values (NaN, infinities, zero, huge, negative, random formats and
//! layouts, random handles), thousands of cases per entry point. Each call must return, never
//! panic (these tests run in a debug build: arithmetic overflow panics), and every refusal must
//! be a typed error that names the field; after every case the context must still work.
//! Accepted tasks are dropped with their container, not built: their images are the test's real ones, but a hostile
//! value the checks let through on purpose (a format the image was not made with, say) is the
//! engine's word and not the SDK's to verify.
mod common;
use ash::vk;
use common::*;
use glam::{Affine3A, Mat3, Mat4, Vec3};
use hybrid_rt::*;
use hybrid_rt_testkit::host::{Host, HostBuffer, HostImage};
use hybrid_rt_testkit::reference::Camera;
use hybrid_rt_testkit::sdk_scene::*;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

/// Cases per entry point.
const CASES: u32 = 2000;

/// Hostile and ordinary floats.
fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(f32::NEG_INFINITY),
        Just(0.0),
        Just(-0.0),
        Just(f32::MAX),
        Just(f32::MIN),
        Just(f32::MIN_POSITIVE),
        Just(1e-30),
        -1e6f32..1e6f32,
        -2.0f32..2.0,
    ]
}

/// Hostile and ordinary unsigned integers.
fn any_u32() -> impl Strategy<Value = u32> {
    prop_oneof![Just(0), Just(1), Just(u32::MAX), Just(u32::MAX / 2 + 1), Just(65_536), 0u32..4096, any::<u32>()]
}

/// A field to spoil and the value it gets: `index` picks the field (modulo the entry point's
/// field count), `float`, `int` and `matrix` are the values a field of that kind takes.
#[derive(Debug, Clone)]
struct Spoil {
    index: usize,
    float: f32,
    int: u32,
    raw: i32,
    matrix: [f32; 16],
}

fn spoils() -> impl Strategy<Value = Vec<Spoil>> {
    let one = (any::<usize>(), any_f32(), any_u32(), any::<i32>(), prop::array::uniform16(any_f32()))
        .prop_map(|(index, float, int, raw, matrix)| Spoil { index, float, int, raw, matrix });
    prop::collection::vec(one, 1..=4)
}

/// A format: one the SDK knows, or any raw value.
fn format(raw: i32) -> vk::Format {
    const KNOWN: [vk::Format; 8] = [
        vk::Format::R32_SFLOAT,
        vk::Format::R16G16B16A16_SFLOAT,
        vk::Format::R8G8B8A8_UNORM,
        vk::Format::D32_SFLOAT,
        vk::Format::R32_UINT,
        vk::Format::R32G32_SFLOAT,
        vk::Format::BC1_RGB_UNORM_BLOCK,
        vk::Format::UNDEFINED,
    ];
    if raw % 3 == 0 {
        vk::Format::from_raw(raw)
    } else {
        KNOWN[raw.unsigned_abs() as usize % KNOWN.len()]
    }
}

/// Spoils field `s.index` of a trace task's common inputs (27 fields).
fn spoil_common(c: &mut TraceCommon, s: &Spoil) {
    let m4 = Mat4::from_cols_array(&s.matrix);
    let m3 = Mat3::from_cols_array(&s.matrix[..9].try_into().unwrap());
    match s.index % 27 {
        0 => c.viewport.x = s.int,
        1 => c.viewport.y = s.int,
        2 => c.viewport.width = s.int,
        3 => c.viewport.height = s.int,
        4 => c.viewport.min_depth = s.float,
        5 => c.viewport.max_depth = s.float,
        6 => c.camera.world_to_view = m4,
        7 => c.camera.view_to_clip = m4,
        8 => c.depth.image.format = format(s.raw),
        9 => c.depth.image.width = s.int,
        10 => c.depth.image.layout = vk::ImageLayout::from_raw(s.raw),
        11 => c.depth.image.view = vk::ImageView::null(),
        12 => c.normals.image.format = format(s.raw),
        13 => {
            c.normals.space = NormalSpace::Custom;
            c.normals.normal_to_world = m3;
        }
        14 => c.roughness.global_roughness = s.float,
        15 => c.roughness.min_roughness = s.float,
        16 => c.roughness.max_roughness = s.float,
        17 => (c.roughness.channel_mask, c.roughness.roughness_multiplier) = ([s.float; 4], s.matrix[0]),
        18 => c.ray_offset.world_threshold = s.float,
        19 => c.ray_offset.cam_linear = s.float,
        20 => c.ray_offset.world_int_scale = s.float,
        21 => {
            c.input_mask = c.depth.image;
            c.input_mask.format = format(s.raw);
        }
        22 => c.input_mask = ImageInput { height: s.int, ..c.depth.image },
        23 => {
            c.direct_lighting = c.depth.image;
            c.direct_lighting.format = format(s.raw);
        }
        24 => c.depth.image.usage = vk::ImageUsageFlags::from_raw(s.int),
        25 => {
            c.half_resolution_mode =
                [HalfResolutionMode::Off, HalfResolutionMode::Checkerboard, HalfResolutionMode::CheckerboardInverted]
                    [s.int as usize % 3]
        }
        _ => c.depth.image.height = s.int,
    }
}

/// Spoils an image input (the task's output): 5 fields.
fn spoil_image(i: &mut ImageInput, s: &Spoil) {
    match s.index % 5 {
        0 => i.format = format(s.raw),
        1 => i.width = s.int,
        2 => i.layout = vk::ImageLayout::from_raw(s.raw),
        3 => i.usage = vk::ImageUsageFlags::from_raw(s.int),
        _ => i.image = vk::Image::null(),
    }
}

/// An error is a refusal of the input (not a Vulkan or internal failure) and names what it
/// refuses: a `Struct.field` path (a refused handle, the field that held it).
fn check_refusal(e: &Error) -> Result<(), TestCaseError> {
    let text = e.to_string();
    let names_field = text.split(|c: char| c.is_whitespace() || c == ':' || c == '(').any(|w| {
        let mut parts = w.splitn(2, '.');
        matches!((parts.next(), parts.next()), (Some(a), Some(b)) if a.starts_with(char::is_uppercase) && !b.is_empty())
    });
    match e {
        Error::InvalidInput { .. }
        | Error::UnsupportedFormat { .. }
        | Error::BufferTooSmall { .. }
        | Error::InvalidTransform { .. } => {
            prop_assert!(names_field, "the error names no field: {text}")
        }
        Error::InvalidHandle { field, .. } => {
            prop_assert!(names_field && text.starts_with(field), "the handle error names no field: {text}")
        }
        other => prop_assert!(false, "not a refusal of the input: {other}"),
    }
    Ok(())
}

struct Fixture {
    host: Host,
    ctx: ExecuteContext,
    images: GBufferImages,
    camera: Camera,
    /// A sampled storage image of the AO output's format: a denoise task's input.
    noisy: HostImage,
    /// A triangle's vertices and indices.
    triangle: [HostBuffer; 2],
}

fn fixture() -> Fixture {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (_, camera, images) = ground_view(&host);
    let format = images.ao_task(&camera, 1.0, 1).output.format;
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED;
    let noisy = host.image_cleared(format, 16, 16, usage, vk::ImageLayout::GENERAL).unwrap();
    let triangle =
        [&[0u8; 36][..], &[0u8; 12][..]].map(|data| host.buffer_with_data(data, vk::BufferUsageFlags::TRANSFER_SRC).unwrap());
    Fixture { host, ctx, images, camera, noisy, triangle }
}

impl Fixture {
    /// Runs `case` on CASES random spoil lists, then an ordinary frame (the context still
    /// works), then checks the validation layer saw nothing.
    fn run(self, case: impl Fn(&Fixture, &mut TaskContainer, &[Spoil]) -> Result<(), TestCaseError>) {
        let mut runner = TestRunner::new(Config { cases: CASES, failure_persistence: None, ..Config::default() });
        runner
            .run(&spoils(), |s| {
                let mut frame = self.ctx.create_task_container();
                case(&self, &mut frame, &s)
            })
            .unwrap();
        let mut frame = self.ctx.create_task_container();
        frame.schedule_ambient_occlusion(&self.images.ao_task(&self.camera, 1.0, 1)).unwrap();
        run_frame(&self.host, &self.ctx, &mut frame).unwrap();
        self.images.destroy(&self.host);
        drop(self.ctx);
        self.host.destroy_image(self.noisy);
        for b in self.triangle {
            self.host.destroy_buffer(b);
        }
        drop(self.host);
        assert_no_validation_errors();
    }
}

#[test]
fn trace_tasks_refuse_hostile_inputs_by_name() {
    fixture().run(|f, frame, spoils| {
        let mut ao = f.images.ao_task(&f.camera, 1.0, 1);
        let mut shadow = TraceShadowTask { common: ao.common, output: ao.output, ..Default::default() };
        for s in spoils {
            match s.index % 4 {
                0 => spoil_common(&mut ao.common, s),
                1 => spoil_image(&mut ao.output, s),
                2 => match s.index % 3 {
                    0 => ao.ray_length = s.float,
                    1 => ao.rays_per_pixel = s.int,
                    _ => ao.falloff_power = s.float,
                },
                _ => {
                    let l = &mut shadow.light;
                    match s.index % 7 {
                        0 => l.position = Vec3::splat(s.float),
                        1 => l.direction = Vec3::new(s.float, s.matrix[0], s.matrix[1]),
                        2 => l.radius = s.float,
                        3 => l.angular_extent = s.float,
                        4 => (l.inner_cone, l.outer_cone) = (s.float, s.matrix[0]),
                        5 => l.range = s.float,
                        _ => l.intensity = s.float,
                    }
                    shadow.rays_per_pixel = s.int % 80;
                }
            }
            shadow.common = ao.common;
        }
        for result in [frame.schedule_ambient_occlusion(&ao), frame.schedule_shadow(&shadow)] {
            if let Err(e) = result {
                check_refusal(&e)?;
            }
        }
        Ok(())
    });
}

#[test]
fn denoise_tasks_refuse_hostile_inputs_by_name() {
    let f = fixture();
    let input =
        DenoisingContextInput { max_width: 16, max_height: 16, signal: SignalType::DiffuseOcclusion, ..Default::default() };
    let context = f.ctx.create_denoising_context(&input).unwrap();
    f.run(move |f, frame, spoils| {
        let ao = f.images.ao_task(&f.camera, 1.0, 1);
        let mut task = DenoiseDiffuseOcclusionTask {
            context,
            common: f.images.denoising_common(&f.camera),
            input: f.noisy.input(vk::ImageLayout::GENERAL),
            output: ao.output,
        };
        for s in spoils {
            let d = &mut task.common;
            match s.index % 5 {
                0 => {
                    let mut t = TraceCommon {
                        depth: d.depth,
                        normals: d.normals,
                        viewport: d.viewport,
                        camera: d.camera,
                        roughness: d.roughness,
                        input_mask: d.input_mask,
                        ..Default::default()
                    };
                    spoil_common(&mut t, s);
                    (d.depth, d.normals, d.viewport, d.camera, d.roughness, d.input_mask) =
                        (t.depth, t.normals, t.viewport, t.camera, t.roughness, t.input_mask);
                }
                1 => spoil_image(if s.int & 1 == 0 { &mut task.input } else { &mut task.output }, s),
                2 => match s.index % 4 {
                    0 => {
                        d.previous_camera =
                            Some(hybrid_rt::Camera { world_to_view: Mat4::from_cols_array(&s.matrix), ..d.camera })
                    }
                    1 => d.camera_jitter = [s.float, s.matrix[0]],
                    2 => d.motion.scale = [s.float; 3],
                    _ => d.motion.image = ImageInput { format: format(s.raw), ..ao.output },
                },
                3 => {
                    let st = &mut d.settings;
                    match s.index % 10 {
                        0 => st.max_history_frames = s.int,
                        1 => st.fast_history_frames = s.int,
                        2 => st.history_clamp_sigma = s.float,
                        3 => st.spatial_passes = s.int,
                        4 => st.luminance_sigma = s.float,
                        5 => st.normal_power = s.float,
                        6 => st.plane_distance_sigma = s.float,
                        7 => st.max_shadow_blur_radius = s.float,
                        8 => st.fresh_history_taps = s.int,
                        _ => st.moving_object_reach = s.float,
                    }
                }
                _ => task.context = DenoisingContextHandle(s.raw as u64 ^ ((s.int as u64) << 32)),
            }
        }
        if let Err(e) = frame.schedule_denoise_diffuse_occlusion(&task) {
            check_refusal(&e)?;
            if let Error::InvalidInput { what, .. } | Error::UnsupportedFormat { what, .. } = &e {
                prop_assert!(!what.starts_with("TraceCommon"), "a denoise task's error names TraceCommon: {e}");
            }
        }
        Ok(())
    });
}

#[test]
fn scene_tasks_refuse_hostile_inputs_by_name() {
    let f = fixture();
    let geometry = f.ctx.create_geometry_handles(1)[0];
    let instance = f.ctx.create_instance_handles(1)[0];
    let (vb, ib) = (f.triangle[0].buffer, f.triangle[1].buffer);
    f.run(move |_, frame, spoils| {
        let mut input = GeometryInput {
            vertices: VertexBufferInput { buffer: vb, count: 3, ..Default::default() },
            indices: IndexBufferInput { buffer: ib, count: 3, ..Default::default() },
            ..Default::default()
        };
        let mut transform = Affine3A::IDENTITY;
        for s in spoils {
            let (v, i) = (&mut input.vertices, &mut input.indices);
            match s.index % 10 {
                0 => v.stride = (s.int as u64).wrapping_mul(s.raw as u64 | 1),
                1 => v.count = s.int,
                2 => v.stride = s.int as u64,
                3 => v.offset = (s.int as u64).wrapping_mul(s.raw as u64),
                4 => v.format = format(s.raw),
                5 => i.format = format(s.raw),
                6 => i.count = s.int,
                7 => i.offset = (s.int as u64).wrapping_mul(s.raw as u64),
                8 => input.transform = Some(Affine3A::from_mat4(Mat4::from_cols_array(&s.matrix))),
                _ => transform = Affine3A::from_mat4(Mat4::from_cols_array(&s.matrix)),
            }
        }
        let task = GeometryTask { handle: geometry, operation: TaskOperation::Register, input };
        // SAFETY: the engine's buffers the task names are alive.
        if let Err(e) = unsafe { frame.schedule_geometry(&task) } {
            check_refusal(&e)?;
        }
        let placed = InstanceInput { geometry, transform, ..Default::default() };
        let task = InstanceTask { handle: instance, operation: InstanceOperation::Register, input: placed };
        if let Err(e) = frame.schedule_instance(&task) {
            check_refusal(&e)?;
        }
        Ok(())
    });
}
