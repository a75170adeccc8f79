//! What the validation layer's GPU-assisted mode makes of push descriptors, the way every pass
//! of the SDK binds its resources.
//!
//! Under GPU-assisted validation the layer installed by scripts/setup.sh (Debian 12's 1.3.239)
//! reports "Descriptor uninitialized" for the SDK's passes, and the instrumented shaders then
//! skip the accesses it calls uninitialized (the SDK's traces come out as NaN). The case below shows that it is the layer's
//! bookkeeping of push descriptors (fixed upstream in Vulkan-ValidationLayers pull request 5744,
//! released after 1.3.239), not the SDK: one compute shader reading a uniform buffer, run once
//! with its descriptors pushed and once with them in an ordinary bound set, the same buffers
//! and the same shader. Without the layer both give the right answer.
use ash::{khr, vk};
use hybrid_rt_testkit::host::{Host, HostBuffer};

/// Reads a uniform buffer (set 0, binding 0) and writes value + 1 to a storage buffer (binding 1).
const SHADER: &str = "#version 450
layout(local_size_x = 1) in;
layout(set = 0, binding = 0) uniform Constants { uint value; } u;
layout(set = 0, binding = 1) buffer Result { uint value; } o;
void main() { o.value = u.value + 1u; }
";

fn compile(source: &str) -> Vec<u32> {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let (src, spv) = (dir.join("gpu_assisted.comp"), dir.join("gpu_assisted.spv"));
    std::fs::write(&src, source).unwrap();
    let compiler = std::env::var("GLSLANG_VALIDATOR").unwrap_or_else(|_| "glslangValidator".into());
    let status = std::process::Command::new(&compiler)
        // SPIR-V 1.5, as the SDK's compute shaders: 1.6's LocalSizeId needs maintenance4.
        .args(["-V", "--target-env", "vulkan1.2", "-o"])
        .arg(&spv)
        .arg(&src)
        .status()
        .expect("run glslangValidator (scripts/setup.sh installs it)");
    assert!(status.success(), "the shader did not compile");
    ash::util::read_spv(&mut std::fs::File::open(&spv).unwrap()).unwrap()
}

/// Runs the shader once, its two buffers pushed (`push`) or in a bound descriptor set, and
/// returns what it wrote.
fn run(host: &Host, module: vk::ShaderModule, push: bool, constants: &HostBuffer, result: &HostBuffer) -> u32 {
    let d = &host.device;
    let stage = vk::ShaderStageFlags::COMPUTE;
    let bindings = [
        vk::DescriptorSetLayoutBinding::default()
            .binding(0)
            .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
            .descriptor_count(1)
            .stage_flags(stage),
        vk::DescriptorSetLayoutBinding::default()
            .binding(1)
            .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
            .descriptor_count(1)
            .stage_flags(stage),
    ];
    let flags =
        if push { vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR } else { vk::DescriptorSetLayoutCreateFlags::empty() };
    let info = vk::DescriptorSetLayoutCreateInfo::default().flags(flags).bindings(&bindings);
    let set_layout = unsafe { d.create_descriptor_set_layout(&info, None) }.unwrap();
    let layouts = [set_layout];
    let layout =
        unsafe { d.create_pipeline_layout(&vk::PipelineLayoutCreateInfo::default().set_layouts(&layouts), None) }.unwrap();
    let entry = c"main";
    let stage_info = vk::PipelineShaderStageCreateInfo::default().stage(stage).module(module).name(entry);
    let pipeline_info = [vk::ComputePipelineCreateInfo::default().stage(stage_info).layout(layout)];
    let pipeline = unsafe { d.create_compute_pipelines(vk::PipelineCache::null(), &pipeline_info, None) }.unwrap()[0];
    let ubo = [vk::DescriptorBufferInfo { buffer: constants.buffer, offset: 0, range: 4 }];
    let ssbo = [vk::DescriptorBufferInfo { buffer: result.buffer, offset: 0, range: 4 }];
    let writes = |set| {
        [
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                .buffer_info(&ubo),
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&ssbo),
        ]
    };
    let sizes = [
        vk::DescriptorPoolSize { ty: vk::DescriptorType::UNIFORM_BUFFER, descriptor_count: 1 },
        vk::DescriptorPoolSize { ty: vk::DescriptorType::STORAGE_BUFFER, descriptor_count: 1 },
    ];
    let pool = unsafe { d.create_descriptor_pool(&vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes), None) }
        .unwrap();
    let set = if push {
        vk::DescriptorSet::null()
    } else {
        let info = vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&layouts);
        let set = unsafe { d.allocate_descriptor_sets(&info) }.unwrap()[0];
        unsafe { d.update_descriptor_sets(&writes(set), &[]) };
        set
    };
    let pusher = khr::push_descriptor::Device::new(&host.instance, d);
    host.run(|cmd| unsafe {
        d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipeline);
        if push {
            pusher.cmd_push_descriptor_set(cmd, vk::PipelineBindPoint::COMPUTE, layout, 0, &writes(vk::DescriptorSet::null()));
        } else {
            d.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, layout, 0, &[set], &[]);
        }
        d.cmd_dispatch(cmd, 1, 1, 1);
        let to_host = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
            .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::HOST)
            .dst_access_mask(vk::AccessFlags2::HOST_READ)];
        d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&to_host));
    })
    .unwrap();
    unsafe {
        d.destroy_descriptor_pool(pool, None);
        d.destroy_pipeline(pipeline, None);
        d.destroy_pipeline_layout(layout, None);
        d.destroy_descriptor_set_layout(set_layout, None);
    }
    u32::from_le_bytes(result.mapped_bytes().expect("a host-visible result")[..4].try_into().unwrap())
}

/// Under GPU-assisted validation, the bound set is checked clean and reads its buffer; pushed
/// descriptors are either handled alike (a layer with the fix) or reported uninitialized and
/// kept from the shader (Debian 12's 1.3.239) — the layer's error, as the bound run of the
/// same shader shows. Either way nothing else is reported.
#[test]
fn gpu_assisted_validation_misreads_push_descriptors() {
    // The only test of this binary, so no other thread reads the environment meanwhile.
    std::env::set_var("HRT_GPU_ASSISTED", "1");
    let host = Host::new().unwrap();
    if !host.validation_enabled {
        eprintln!("no validation layer installed: nothing to show (scripts/setup.sh installs it)");
        return;
    }
    let code = compile(SHADER);
    let module = unsafe { host.device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&code), None) }.unwrap();
    let constants = host.buffer_with_data(&41u32.to_le_bytes(), vk::BufferUsageFlags::UNIFORM_BUFFER).unwrap();
    let results = [0, 1].map(|_| host.buffer_with_data(&[0u8; 4], vk::BufferUsageFlags::STORAGE_BUFFER).unwrap());

    let bound = run(&host, module, false, &constants, &results[0]);
    let bound_problems = host.take_validation_problems();
    assert_eq!(bound, 42, "the bound set's shader read its uniform buffer");
    assert!(bound_problems.is_empty(), "a bound set, checked by GPU-assisted validation: {bound_problems:#?}");

    let pushed = run(&host, module, true, &constants, &results[1]);
    let pushed_problems = host.take_validation_problems();
    eprintln!("pushed descriptors: the shader wrote {pushed}; the layer reported {pushed_problems:#?}");
    if pushed_problems.is_empty() {
        assert_eq!(pushed, 42, "a layer that handles push descriptors leaves the shader alone");
    } else {
        assert!(
            pushed_problems.iter().all(|p| p.contains("Descriptor uninitialized")),
            "only the layer's push-descriptor bookkeeping: {pushed_problems:#?}"
        );
        // The instrumented shader skips what it calls uninitialized: the result keeps its 0.
        assert_ne!(pushed, 42, "a layer that reports the pushed buffers uninitialized also keeps the shader from them");
    }
    unsafe { host.device.destroy_shader_module(module, None) };
    host.destroy_buffer(constants);
    for r in results {
        host.destroy_buffer(r);
    }
}
