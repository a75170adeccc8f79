//! A minimal headless "engine" for the sample, the bench and the tests: it creates the Vulkan
//! instance and device the way an engine integrating hybrid-rt would (enabling what
//! `hybrid_rt::REQUIRED_DEVICE_EXTENSIONS` and `DeviceFeatures` ask for), owns a queue and
//! command buffers, and moves images and buffers between host and GPU. `scene` holds the
//! triangle scenes it renders (meshes, instances, a camera), which the test kit's CPU reference
//! renderer traces too.
//!
//! The Khronos validation layer is enabled when installed (set HRT_VALIDATION=0 to turn it
//! off), with synchronization validation (HRT_SYNC_VALIDATION=0 turns that part off) and,
//! with HRT_BEST_PRACTICES=1, the best-practices checks, and with HRT_GPU_ASSISTED=1 its
//! GPU-assisted checks of shader accesses (the layer's own settings, e.g. in a
//! vk_layer_settings.txt, choose which). Every error and warning it reports
//! about this host's instance is counted per host, and dropping a host that saw any panics with
//! the messages: a test passes only with a clean log, whether or not it asks. Warnings on the
//! short list in `IGNORED_WARNINGS` (each says why) are logged, not counted.
//! Device choice: the first device with ray tracing, or the first whose name contains
//! HRT_DEVICE (e.g. HRT_DEVICE=llvmpipe).
use ash::{ext, vk};
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme, Allocator, AllocatorCreateDesc};
use gpu_allocator::{AllocationSizes, MemoryLocation};
use hybrid_rt::{DeviceDesc, DeviceFeatures};
use std::ffi::{c_void, CStr};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

pub mod scene;

/// Errors and counted warnings of every host of the process (what `Host::validation_errors`
/// reports).
static VALIDATION_ERRORS: AtomicUsize = AtomicUsize::new(0);
static VALIDATION_MESSAGES: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// Warnings that are not counted, by message id, each with the reason. Everything else the
/// layer says fails the test.
/// The best-practices checks among them can only come from calls the test host makes and the
/// SDK never does (the SDK allocates through gpu-allocator's large blocks, creates no command
/// pools and submits nothing), so they say nothing about the SDK.
const IGNORED_WARNINGS: &[(&str, &str)] =
    &[("UNASSIGNED-BestPractices-vkCreateCommandPool-command-buffer-reset", "the test host resets command buffers one by one")];

/// What the validation layer said about one host's instance (the messenger's user data).
#[derive(Default)]
struct ValidationLog {
    problems: Mutex<Vec<String>>,
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    let text =
        |p: *const std::ffi::c_char| if p.is_null() { String::new() } else { CStr::from_ptr(p).to_string_lossy().into_owned() };
    let (msg, id) = if data.is_null() {
        (String::from("(no message)"), String::new())
    } else {
        (text((*data).p_message), text((*data).p_message_id_name))
    };
    let error = severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR);
    if !error && !severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
        return vk::FALSE;
    }
    if let Some((_, why)) = IGNORED_WARNINGS.iter().find(|(ignored, _)| !error && id == *ignored) {
        log::info!("[vulkan validation, ignored: {why}] {msg}");
        return vk::FALSE;
    }
    let line = format!("{} {msg}", if error { "error:" } else { "warning:" });
    eprintln!("[vulkan validation] {line}");
    VALIDATION_ERRORS.fetch_add(1, Ordering::SeqCst);
    if let Ok(mut m) = VALIDATION_MESSAGES.lock() {
        m.push(line.clone());
    }
    // SAFETY: `user` is the host's boxed log, which outlives its messenger.
    if let Some(log) = (user as *const ValidationLog).as_ref() {
        if let Ok(mut p) = log.problems.lock() {
            p.push(line);
        }
    }
    vk::FALSE
}

fn env_flag(name: &str, default: bool) -> bool {
    std::env::var(name).map(|v| v != "0").unwrap_or(default)
}

pub struct Host {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub enabled_extensions: Vec<&'static CStr>,
    pub validation_enabled: bool,
    pub device_name: String,
    pool: vk::CommandPool,
    /// A queue of a second compute-capable family, where the device has one.
    pub async_compute: Option<AsyncCompute>,
    debug: Option<(ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Boxed: the messenger holds its address.
    validation_log: Box<ValidationLog>,
    /// The feature chain the device was created with (boxed: the chain links their fields;
    /// `ExecuteContext::new` reads it).
    features: Box<EngineFeatures>,
    /// Every buffer and image of the host is suballocated from gpu-allocator's blocks, as an
    /// engine's would be (one `vkAllocateMemory` per resource runs into the driver's allocation
    /// count limit and its per-allocation cost). None only while the host is dropped: the
    /// allocator frees its blocks before the device goes.
    allocator: Mutex<Option<Allocator>>,
}

/// A device-local image with its view.
pub struct HostImage {
    pub image: vk::Image,
    pub view: vk::ImageView,
    allocation: Allocation,
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    pub aspect: vk::ImageAspectFlags,
    /// The usage it was created with (what the SDK's `ImageInput` declares).
    pub usage: vk::ImageUsageFlags,
}

impl HostImage {
    /// The SDK's description of this image in `layout`.
    pub fn input(&self, layout: vk::ImageLayout) -> hybrid_rt::ImageInput {
        hybrid_rt::ImageInput {
            image: self.image,
            view: self.view,
            format: self.format,
            width: self.width,
            height: self.height,
            layout,
            usage: self.usage,
        }
    }
}

pub struct HostBuffer {
    pub buffer: vk::Buffer,
    allocation: Allocation,
    pub size: u64,
    /// Host-visible memory stays mapped for the buffer's life (null otherwise; gpu-allocator
    /// maps each host-visible block once): the sample rewrites its constant and vertex buffers
    /// every frame, and a map/unmap per write is a driver call per buffer per frame for nothing.
    mapped: *mut u8,
}

impl HostBuffer {
    /// The bytes of a host-visible buffer (None for device-local memory). Read them after the
    /// GPU's writes have finished and were made visible to the host.
    pub fn mapped_bytes(&self) -> Option<&[u8]> {
        // SAFETY: `mapped` covers `size` bytes for the buffer's life.
        (!self.mapped.is_null()).then(|| unsafe { std::slice::from_raw_parts(self.mapped, self.size as usize) })
    }
}

pub type HostResult<T> = Result<T, String>;

/// A queue of a second compute family and its command pool.
pub struct AsyncCompute {
    pub queue: vk::Queue,
    pub family: u32,
    pub pool: vk::CommandPool,
}

/// The host's own device features with the SDK's merged in (`DeviceFeatures::merge_into`).
struct EngineFeatures {
    features2: vk::PhysicalDeviceFeatures2<'static>,
    vulkan13: vk::PhysicalDeviceVulkan13Features<'static>,
    sdk: DeviceFeatures,
}

impl EngineFeatures {
    fn chain(&self) -> *const c_void {
        &self.features2 as *const _ as *const c_void
    }
}

/// The Vulkan version the host's instance asks for.
pub const API_VERSION: u32 = vk::API_VERSION_1_3;

/// Every stage the host, the sample and the SDK run work in: what a "full" barrier of theirs
/// waits for and blocks. (ALL_COMMANDS would say the same and draw a best-practices warning.)
pub const WORK_STAGES: vk::PipelineStageFlags2 = vk::PipelineStageFlags2::from_raw(
    vk::PipelineStageFlags2::COPY.as_raw()
        | vk::PipelineStageFlags2::BLIT.as_raw()
        | vk::PipelineStageFlags2::CLEAR.as_raw()
        | vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR.as_raw()
        | vk::PipelineStageFlags2::COMPUTE_SHADER.as_raw()
        | vk::PipelineStageFlags2::RAY_TRACING_SHADER_KHR.as_raw()
        | vk::PipelineStageFlags2::VERTEX_INPUT.as_raw()
        | vk::PipelineStageFlags2::VERTEX_SHADER.as_raw()
        | vk::PipelineStageFlags2::FRAGMENT_SHADER.as_raw()
        | vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS.as_raw()
        | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS.as_raw()
        | vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT.as_raw(),
);

/// The accesses an image in `layout` is used with: what a barrier leaving the layout (`src`)
/// waits for, or entering it makes visible.
pub fn layout_access(layout: vk::ImageLayout, src: bool) -> vk::AccessFlags2 {
    use vk::AccessFlags2 as A;
    use vk::ImageLayout as L;
    match layout {
        L::UNDEFINED | L::PRESENT_SRC_KHR => A::NONE,
        L::TRANSFER_DST_OPTIMAL => A::TRANSFER_WRITE,
        L::TRANSFER_SRC_OPTIMAL => A::TRANSFER_READ,
        L::SHADER_READ_ONLY_OPTIMAL | L::DEPTH_READ_ONLY_OPTIMAL | L::DEPTH_STENCIL_READ_ONLY_OPTIMAL | L::READ_ONLY_OPTIMAL => {
            A::SHADER_READ
        }
        L::COLOR_ATTACHMENT_OPTIMAL => A::COLOR_ATTACHMENT_WRITE | A::COLOR_ATTACHMENT_READ,
        L::DEPTH_ATTACHMENT_OPTIMAL | L::DEPTH_STENCIL_ATTACHMENT_OPTIMAL => {
            A::DEPTH_STENCIL_ATTACHMENT_WRITE | A::DEPTH_STENCIL_ATTACHMENT_READ
        }
        _ if src => A::MEMORY_WRITE,
        _ => A::MEMORY_READ | A::MEMORY_WRITE,
    }
}

pub fn vkerr(what: &'static str) -> impl Fn(vk::Result) -> String {
    move |e| format!("{what}: {e:?}")
}

/// The instance and what it was created with.
struct InstanceParts {
    instance: ash::Instance,
    validation_enabled: bool,
    has_debug: bool,
}

/// The instance: the validation layer when installed (and wanted), with synchronization
/// validation and, on request, best practices; debug utils where the loader has them; and the
/// caller's extensions.
fn create_instance(entry: &ash::Entry, instance_extensions: &[&CStr]) -> HostResult<InstanceParts> {
    let layers = unsafe { entry.enumerate_instance_layer_properties() }.unwrap_or_default();
    let want_validation = env_flag("HRT_VALIDATION", true);
    let validation_name = c"VK_LAYER_KHRONOS_validation";
    let validation_enabled = want_validation && layers.iter().any(|l| l.layer_name_as_c_str() == Ok(validation_name));
    // A run that must be validated (the device machine's, where the layer is carried) says
    // so: a missing layer is then an error, not a silently unvalidated pass.
    if env_flag("HRT_REQUIRE_VALIDATION", false) && !validation_enabled {
        return Err("HRT_REQUIRE_VALIDATION=1 but VK_LAYER_KHRONOS_validation is not available".into());
    }
    let exts = unsafe { entry.enumerate_instance_extension_properties(None) }.unwrap_or_default();
    let has_debug = exts.iter().any(|e| e.extension_name_as_c_str() == Ok(ext::debug_utils::NAME));

    let app = vk::ApplicationInfo::default().application_name(c"hybrid-rt host").api_version(API_VERSION);
    let layer_names: Vec<*const i8> = if validation_enabled { vec![validation_name.as_ptr()] } else { vec![] };
    let mut ext_names: Vec<*const i8> = if has_debug { vec![ext::debug_utils::NAME.as_ptr()] } else { vec![] };
    ext_names.extend(instance_extensions.iter().map(|e| e.as_ptr()));
    let info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layer_names)
        .enabled_extension_names(&ext_names);
    // Synchronization validation always (it found real hazards); best practices on request.
    let mut checks = Vec::new();
    if env_flag("HRT_SYNC_VALIDATION", true) {
        checks.push(vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION);
    }
    if env_flag("HRT_BEST_PRACTICES", false) {
        checks.push(vk::ValidationFeatureEnableEXT::BEST_PRACTICES);
    }
    if env_flag("HRT_GPU_ASSISTED", false) {
        checks.push(vk::ValidationFeatureEnableEXT::GPU_ASSISTED);
    }
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&checks);
    let info = if validation_enabled && !checks.is_empty() { info.push_next(&mut features) } else { info };
    let instance = unsafe { entry.create_instance(&info, None) }.map_err(vkerr("vkCreateInstance"))?;
    Ok(InstanceParts { instance, validation_enabled, has_debug })
}

/// A messenger that logs what the validation layer says about `instance` into `log` (which
/// must outlive it).
fn create_messenger(
    entry: &ash::Entry,
    instance: &ash::Instance,
    log: &ValidationLog,
) -> HostResult<(ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)> {
    let loader = ext::debug_utils::Instance::new(entry, instance);
    let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING)
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(debug_callback))
        .user_data(log as *const ValidationLog as *mut c_void);
    let m = unsafe { loader.create_debug_utils_messenger(&info, None) }.map_err(vkerr("debug messenger"))?;
    Ok((loader, m))
}

/// The first device with everything the SDK needs (and, with HRT_DEVICE, a name containing
/// it): the device, its name and what it supports.
fn choose_device(instance: &ash::Instance) -> HostResult<(vk::PhysicalDevice, String, hybrid_rt::DeviceSupport)> {
    let wanted = std::env::var("HRT_DEVICE").ok();
    let pdevs = unsafe { instance.enumerate_physical_devices() }.map_err(vkerr("enumerate devices"))?;
    let mut chosen = None;
    let mut seen = Vec::new();
    for pd in pdevs {
        let props = unsafe { instance.get_physical_device_properties(pd) };
        let name = props.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let support = hybrid_rt::query_device_support(instance, pd);
        seen.push(format!("{name}: {:?}", support.missing));
        let name_ok = match &wanted {
            Some(w) => name.contains(w.as_str()),
            None => true,
        };
        if support.supported && name_ok {
            chosen = Some((pd, name, support));
            break;
        }
    }
    chosen.ok_or_else(|| format!("no Vulkan device with ray tracing (run scripts/setup.sh); seen: {seen:?}"))
}

impl Host {
    pub fn new() -> HostResult<Host> {
        Self::with_extensions(&[], &[])
    }

    /// `new` with extra instance extensions (a window's surface extensions) and device
    /// extensions (`VK_KHR_swapchain`); the queue must then also present, which the caller
    /// checks against its surface.
    pub fn with_extensions(instance_extensions: &[&CStr], device_extensions: &[&'static CStr]) -> HostResult<Host> {
        let entry = unsafe { ash::Entry::load() }.map_err(|e| format!("no Vulkan loader: {e}"))?;
        let InstanceParts { instance, validation_enabled, has_debug } = create_instance(&entry, instance_extensions)?;
        let validation_log = Box::<ValidationLog>::default();
        let debug = if has_debug { Some(create_messenger(&entry, &instance, &validation_log)?) } else { None };
        let (physical_device, device_name, support) = choose_device(&instance)?;

        let families = unsafe { instance.get_physical_device_queue_family_properties(physical_device) };
        let queue_family = families
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE | vk::QueueFlags::GRAPHICS))
            .or_else(|| families.iter().position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE)))
            .ok_or("no compute queue")? as u32;
        let mut enabled_extensions: Vec<&'static CStr> = hybrid_rt::REQUIRED_DEVICE_EXTENSIONS.to_vec();
        let disable_rq = std::env::var("HRT_DISABLE_RAY_QUERY").is_ok_and(|v| v != "0");
        if support.ray_query && !disable_rq {
            enabled_extensions.extend_from_slice(hybrid_rt::OPTIONAL_DEVICE_EXTENSIONS);
        }
        enabled_extensions.extend_from_slice(device_extensions);
        let ext_ptrs: Vec<*const i8> = enabled_extensions.iter().map(|e| e.as_ptr()).collect();
        let priorities = [1.0f32];
        // A second, compute-capable family where the device has one (an async-compute queue:
        // NVIDIA has; lavapipe has a single family).
        // HRT_ASYNC_COMPUTE=0 leaves it out (diagnosis).
        let async_family = families
            .iter()
            .enumerate()
            .position(|(i, f)| i as u32 != queue_family && f.queue_flags.contains(vk::QueueFlags::COMPUTE))
            .map(|i| i as u32)
            .filter(|_| env_flag("HRT_ASYNC_COMPUTE", true));
        let mut queues =
            vec![vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family).queue_priorities(&priorities)];
        if let Some(f) = async_family {
            queues.push(vk::DeviceQueueCreateInfo::default().queue_family_index(f).queue_priorities(&priorities));
        }
        // Like an engine with a feature chain of its own (it rasterizes too: the sample's
        // G-buffer uses dynamic rendering), the SDK's features are merged into it.
        let mut features = Box::new(EngineFeatures {
            features2: vk::PhysicalDeviceFeatures2::default(),
            vulkan13: vk::PhysicalDeviceVulkan13Features::default().dynamic_rendering(true),
            sdk: DeviceFeatures::required(support.ray_query && !disable_rq),
        });
        features.features2.p_next = &mut features.vulkan13 as *mut _ as *mut c_void;
        let EngineFeatures { features2, sdk, .. } = &mut *features;
        // SAFETY: the chain is the box's own structs, which stay in place for the host's life.
        unsafe { sdk.merge_into(features2) };
        let mut info = vk::DeviceCreateInfo::default().queue_create_infos(&queues).enabled_extension_names(&ext_ptrs);
        info.p_next = features.chain();
        let device = unsafe { instance.create_device(physical_device, &info, None) }.map_err(vkerr("vkCreateDevice"))?;
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        let pool = unsafe { device.create_command_pool(&pool_info, None) }.map_err(vkerr("command pool"))?;
        let async_compute = match async_family {
            Some(f) => {
                let info = vk::CommandPoolCreateInfo::default()
                    .queue_family_index(f)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
                let p = unsafe { device.create_command_pool(&info, None) }.map_err(vkerr("command pool"))?;
                Some(AsyncCompute { queue: unsafe { device.get_device_queue(f, 0) }, family: f, pool: p })
            }
            None => None,
        };
        // Blocks of 64 MiB (gpu-allocator's default is 256 MiB of device memory): tests make a
        // host each, and lavapipe's device memory is the process's own.
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device,
            debug_settings: Default::default(),
            // The bench's BLAS floor builds from these buffers' addresses (the device has the
            // feature: the SDK requires it).
            buffer_device_address: true,
            allocation_sizes: AllocationSizes::new(64 << 20, 64 << 20),
        })
        .map_err(|e| format!("gpu-allocator: {e}"))?;
        Ok(Host {
            entry,
            instance,
            physical_device,
            device,
            queue,
            queue_family,
            enabled_extensions,
            validation_enabled,
            device_name,
            pool,
            async_compute,
            debug,
            validation_log,
            features,
            allocator: Mutex::new(Some(allocator)),
        })
    }

    /// What `hybrid_rt::ExecuteContext::new` takes.
    pub fn device_desc(&self) -> DeviceDesc<'_> {
        DeviceDesc::new(&self.entry, &self.instance, self.physical_device, &self.device)
            .enabled_extensions(&self.enabled_extensions)
            .instance_api_version(API_VERSION)
            .enabled_features(self.features.chain())
            // HRT_DEBUG_UTILS=0: the SDK names nothing and labels nothing (diagnosis).
            .with_debug_utils(self.debug.is_some() && env_flag("HRT_DEBUG_UTILS", true))
    }

    /// An SDK context on this host's device.
    pub fn create_context(&self, settings: &hybrid_rt::InitSettings) -> hybrid_rt::Result<hybrid_rt::ExecuteContext> {
        // SAFETY: the host's handles belong together, its device was created with exactly these
        // extensions and this feature chain, and it outlives every context (drop order: tests
        // drop their context before the host, and the host waits for its queue before
        // destroying the device).
        unsafe { hybrid_rt::ExecuteContext::new(&self.device_desc(), settings) }
    }

    /// Validation errors and counted warnings reported so far by this host's instance.
    pub fn validation_problems(&self) -> Vec<String> {
        self.validation_log.problems.lock().map(|p| p.clone()).unwrap_or_default()
    }

    /// Takes the validation errors and counted warnings this host's instance reported so far,
    /// so a test that provokes them on purpose can check them and still drop the host cleanly.
    pub fn take_validation_problems(&self) -> Vec<String> {
        self.validation_log.problems.lock().map(|mut p| std::mem::take(&mut *p)).unwrap_or_default()
    }

    /// Validation errors and counted warnings reported so far in this process.
    pub fn validation_errors() -> usize {
        VALIDATION_ERRORS.load(Ordering::SeqCst)
    }

    pub fn validation_messages() -> Vec<String> {
        VALIDATION_MESSAGES.lock().map(|m| m.clone()).unwrap_or_default()
    }

    pub fn is_lavapipe(&self) -> bool {
        self.device_name.contains("llvmpipe")
    }

    pub fn allocate_command_buffer(&self) -> HostResult<vk::CommandBuffer> {
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        Ok(unsafe { self.device.allocate_command_buffers(&info) }.map_err(vkerr("allocate cmd"))?[0])
    }

    pub fn begin(&self, cmd: vk::CommandBuffer) -> HostResult<()> {
        unsafe {
            self.device.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty()).map_err(vkerr("reset cmd"))?;
            self.device
                .begin_command_buffer(
                    cmd,
                    &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                )
                .map_err(vkerr("begin cmd"))
        }
    }

    /// Ends, submits and returns a fence to wait on.
    pub fn submit(&self, cmd: vk::CommandBuffer) -> HostResult<vk::Fence> {
        unsafe {
            self.device.end_command_buffer(cmd).map_err(vkerr("end cmd"))?;
            let fence = self.device.create_fence(&vk::FenceCreateInfo::default(), None).map_err(vkerr("fence"))?;
            let cmds = [cmd];
            let submit = vk::SubmitInfo::default().command_buffers(&cmds);
            self.device.queue_submit(self.queue, &[submit], fence).map_err(vkerr("vkQueueSubmit"))?;
            Ok(fence)
        }
    }

    pub fn wait(&self, fence: vk::Fence) -> HostResult<()> {
        unsafe {
            self.device.wait_for_fences(&[fence], true, u64::MAX).map_err(vkerr("wait fence"))?;
            self.device.destroy_fence(fence, None);
        }
        Ok(())
    }

    /// Frees a command buffer of the host's pool (after its work completed).
    pub fn free_command_buffer(&self, cmd: vk::CommandBuffer) {
        unsafe { self.device.free_command_buffers(self.pool, &[cmd]) };
    }

    /// Records with `f` into a fresh command buffer, submits, and waits.
    pub fn run<R>(&self, f: impl FnOnce(vk::CommandBuffer) -> R) -> HostResult<R> {
        let cmd = self.allocate_command_buffer()?;
        self.begin(cmd)?;
        let r = f(cmd);
        let fence = self.submit(cmd)?;
        self.wait(fence)?;
        unsafe { self.device.free_command_buffers(self.pool, &[cmd]) };
        Ok(r)
    }

    /// Suballocates memory for a resource with these requirements: host-visible memory is
    /// write-combined for uploads (`CpuToGpu`) unless HOST_CACHED is asked for (read-backs).
    fn allocate(
        &self,
        name: &str,
        requirements: vk::MemoryRequirements,
        flags: vk::MemoryPropertyFlags,
        linear: bool,
    ) -> HostResult<Allocation> {
        let location = if flags.contains(vk::MemoryPropertyFlags::HOST_CACHED) {
            MemoryLocation::GpuToCpu
        } else if flags.contains(vk::MemoryPropertyFlags::HOST_VISIBLE) {
            MemoryLocation::CpuToGpu
        } else {
            MemoryLocation::GpuOnly
        };
        let mut guard = self.allocator.lock().unwrap_or_else(|e| e.into_inner());
        let allocator = guard.as_mut().ok_or("the host is being dropped")?;
        allocator
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|e| format!("allocate {name}: {e}"))
    }

    fn free(&self, allocation: Allocation) {
        let mut guard = self.allocator.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(allocator) = guard.as_mut() {
            // Only fails for an allocation of another allocator: nothing to do then.
            let _ = allocator.free(allocation);
        }
    }

    /// A host-visible buffer holding `data` (vertex/index buffers of the test scenes).
    pub fn buffer_with_data(&self, data: &[u8], usage: vk::BufferUsageFlags) -> HostResult<HostBuffer> {
        let b = self.create_buffer(
            data.len().max(4) as u64,
            usage,
            vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT,
        )?;
        self.write_buffer(&b, data)?;
        Ok(b)
    }

    /// A device-local buffer holding `data`, uploaded through a staging buffer (the sample's
    /// static vertex and index buffers: read by every draw and every BLAS build, so they live
    /// in video memory, not in host memory the GPU reads over PCIe).
    pub fn device_buffer_with_data(&self, data: &[u8], usage: vk::BufferUsageFlags) -> HostResult<HostBuffer> {
        let size = data.len().max(4) as u64;
        let b = self.create_buffer(size, usage | vk::BufferUsageFlags::TRANSFER_DST, vk::MemoryPropertyFlags::DEVICE_LOCAL)?;
        let staging = match self.buffer_with_data(data, vk::BufferUsageFlags::TRANSFER_SRC) {
            Ok(s) => s,
            Err(e) => {
                self.destroy_buffer(b);
                return Err(e);
            }
        };
        let copied = self.run(|cmd| {
            let region = vk::BufferCopy { src_offset: 0, dst_offset: 0, size: data.len() as u64 };
            // SAFETY: both buffers are live and at least `data.len()` bytes long.
            if region.size > 0 {
                unsafe { self.device.cmd_copy_buffer(cmd, staging.buffer, b.buffer, &[region]) };
            }
        });
        self.destroy_buffer(staging);
        match copied {
            Ok(()) => Ok(b),
            Err(e) => {
                self.destroy_buffer(b);
                Err(e)
            }
        }
    }

    /// Copies `data` to the start of a host-visible buffer (made by `buffer_with_data`).
    pub fn write_buffer(&self, b: &HostBuffer, data: &[u8]) -> HostResult<()> {
        if data.len() as u64 > b.size {
            return Err(format!("write_buffer: {} bytes into a {}-byte buffer", data.len(), b.size));
        }
        unsafe {
            if b.mapped.is_null() {
                return Err("write_buffer: the buffer is not host-visible".into());
            }
            std::ptr::copy_nonoverlapping(data.as_ptr(), b.mapped, data.len());
        }
        Ok(())
    }

    pub fn create_buffer(
        &self,
        size: u64,
        usage: vk::BufferUsageFlags,
        flags: vk::MemoryPropertyFlags,
    ) -> HostResult<HostBuffer> {
        unsafe {
            let info = vk::BufferCreateInfo::default().size(size).usage(usage);
            let buffer = self.device.create_buffer(&info, None).map_err(vkerr("create buffer"))?;
            let req = self.device.get_buffer_memory_requirements(buffer);
            let allocation = match self.allocate("host buffer", req, flags, true) {
                Ok(a) => a,
                Err(e) => {
                    self.device.destroy_buffer(buffer, None);
                    return Err(e);
                }
            };
            if let Err(e) = self.device.bind_buffer_memory(buffer, allocation.memory(), allocation.offset()) {
                self.device.destroy_buffer(buffer, None);
                self.free(allocation);
                return Err(format!("bind: {e:?}"));
            }
            let mapped = match allocation.mapped_ptr() {
                Some(p) if flags.contains(vk::MemoryPropertyFlags::HOST_VISIBLE) => p.as_ptr() as *mut u8,
                _ => std::ptr::null_mut(),
            };
            Ok(HostBuffer { buffer, allocation, size, mapped })
        }
    }

    pub fn destroy_buffer(&self, b: HostBuffer) {
        // SAFETY: the caller's rule: no pending GPU work uses the buffer.
        unsafe { self.device.destroy_buffer(b.buffer, None) };
        self.free(b.allocation);
    }

    pub fn create_image(&self, format: vk::Format, width: u32, height: u32, usage: vk::ImageUsageFlags) -> HostResult<HostImage> {
        let aspect = match format {
            vk::Format::D32_SFLOAT | vk::Format::D16_UNORM | vk::Format::X8_D24_UNORM_PACK32 => vk::ImageAspectFlags::DEPTH,
            _ => vk::ImageAspectFlags::COLOR,
        };
        unsafe {
            let info = vk::ImageCreateInfo::default()
                .image_type(vk::ImageType::TYPE_2D)
                .format(format)
                .extent(vk::Extent3D { width, height, depth: 1 })
                .mip_levels(1)
                .array_layers(1)
                .samples(vk::SampleCountFlags::TYPE_1)
                .tiling(vk::ImageTiling::OPTIMAL)
                .usage(usage | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST);
            let usage = info.usage;
            let image = self.device.create_image(&info, None).map_err(vkerr("create image"))?;
            let req = self.device.get_image_memory_requirements(image);
            let allocation = match self.allocate("host image", req, vk::MemoryPropertyFlags::DEVICE_LOCAL, false) {
                Ok(a) => a,
                Err(e) => {
                    self.device.destroy_image(image, None);
                    return Err(e);
                }
            };
            if let Err(e) = self.device.bind_image_memory(image, allocation.memory(), allocation.offset()) {
                self.device.destroy_image(image, None);
                self.free(allocation);
                return Err(format!("bind image: {e:?}"));
            }
            let view_info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(format)
                .subresource_range(range(aspect));
            let view = self.device.create_image_view(&view_info, None).map_err(vkerr("create view"))?;
            Ok(HostImage { image, view, allocation, format, width, height, aspect, usage })
        }
    }

    pub fn destroy_image(&self, img: HostImage) {
        unsafe {
            self.device.destroy_image_view(img.view, None);
            self.device.destroy_image(img.image, None);
        }
        self.free(img.allocation);
    }

    /// Records a layout transition after every earlier use of the image (test code: simple >
    /// tight), with the access masks each layout implies.
    pub fn transition(&self, cmd: vk::CommandBuffer, img: &HostImage, from: vk::ImageLayout, to: vk::ImageLayout) {
        let b = [vk::ImageMemoryBarrier2::default()
            .src_stage_mask(WORK_STAGES)
            .src_access_mask(layout_access(from, true))
            .dst_stage_mask(WORK_STAGES)
            .dst_access_mask(layout_access(to, false))
            .old_layout(from)
            .new_layout(to)
            .image(img.image)
            .subresource_range(range(img.aspect))];
        unsafe { self.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&b)) };
    }

    /// A full memory barrier (what an engine places between its work and the SDK's).
    pub fn full_barrier(&self, cmd: vk::CommandBuffer) {
        let b = [vk::MemoryBarrier2::default()
            .src_stage_mask(WORK_STAGES)
            .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
            .dst_stage_mask(WORK_STAGES)
            .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)];
        unsafe { self.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&b)) };
    }

    /// Creates an image holding `texels` (tightly packed, in the format's layout) and leaves it
    /// in `layout`.
    pub fn image_with_data(
        &self,
        format: vk::Format,
        width: u32,
        height: u32,
        usage: vk::ImageUsageFlags,
        texels: &[u8],
        layout: vk::ImageLayout,
    ) -> HostResult<HostImage> {
        let img = self.create_image(format, width, height, usage)?;
        let staging = self.buffer_with_data(texels, vk::BufferUsageFlags::TRANSFER_SRC)?;
        self.run(|cmd| {
            self.transition(cmd, &img, vk::ImageLayout::UNDEFINED, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
            let region = copy_region(&img);
            unsafe {
                self.device.cmd_copy_buffer_to_image(
                    cmd,
                    staging.buffer,
                    img.image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                )
            };
            self.transition(cmd, &img, vk::ImageLayout::TRANSFER_DST_OPTIMAL, layout);
        })?;
        self.destroy_buffer(staging);
        Ok(img)
    }

    /// Replaces the texels of an image that is in `layout` (and stays in it).
    pub fn write_image(&self, img: &HostImage, texels: &[u8], layout: vk::ImageLayout) -> HostResult<()> {
        let staging = self.buffer_with_data(texels, vk::BufferUsageFlags::TRANSFER_SRC)?;
        self.run(|cmd| {
            self.transition(cmd, img, layout, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
            let region = copy_region(img);
            unsafe {
                self.device.cmd_copy_buffer_to_image(
                    cmd,
                    staging.buffer,
                    img.image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                )
            };
            self.transition(cmd, img, vk::ImageLayout::TRANSFER_DST_OPTIMAL, layout);
        })?;
        self.destroy_buffer(staging);
        Ok(())
    }

    /// An image cleared to zero, in `layout` (outputs: GENERAL).
    pub fn image_cleared(
        &self,
        format: vk::Format,
        width: u32,
        height: u32,
        usage: vk::ImageUsageFlags,
        layout: vk::ImageLayout,
    ) -> HostResult<HostImage> {
        let bytes = width as usize * height as usize * texel_size(format);
        self.image_with_data(format, width, height, usage, &vec![0u8; bytes], layout)
    }

    /// Copies the image (currently in `layout`) back to the host; it is left in `layout`.
    pub fn read_image(&self, img: &HostImage, layout: vk::ImageLayout) -> HostResult<Vec<u8>> {
        let size = img.width as u64 * img.height as u64 * texel_size(img.format) as u64;
        let staging = self.create_buffer(
            size,
            vk::BufferUsageFlags::TRANSFER_DST,
            vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_CACHED,
        )?;
        self.run(|cmd| {
            self.transition(cmd, img, layout, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
            unsafe {
                self.device.cmd_copy_image_to_buffer(
                    cmd,
                    img.image,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    staging.buffer,
                    &[copy_region(img)],
                )
            };
            self.transition(cmd, img, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, layout);
        })?;
        let mut out = vec![0u8; size as usize];
        unsafe {
            std::ptr::copy_nonoverlapping(staging.mapped as *const u8, out.as_mut_ptr(), out.len());
        }
        self.destroy_buffer(staging);
        Ok(out)
    }

    /// Reads an R32_SFLOAT (or the first channel of an RGBA32F) image as floats.
    pub fn read_image_f32(&self, img: &HostImage, layout: vk::ImageLayout) -> HostResult<Vec<f32>> {
        let bytes = self.read_image(img, layout)?;
        let all: Vec<f32> = bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        let channels = texel_size(img.format) / 4;
        Ok(all.chunks_exact(channels.max(1)).map(|c| c[0]).collect())
    }
}

impl Drop for Host {
    fn drop(&mut self) {
        // A failing test unwinds past its cleanup: leak the device rather than have the
        // validation layer report those leaks as errors in every other test of the process.
        if std::thread::panicking() {
            return;
        }
        unsafe {
            let _ = self.device.device_wait_idle();
            // The allocator's blocks go before the device (it logs any allocation still live).
            drop(self.allocator.lock().unwrap_or_else(|e| e.into_inner()).take());
            self.device.destroy_command_pool(self.pool, None);
            if let Some(a) = self.async_compute.take() {
                self.device.destroy_command_pool(a.pool, None);
            }
            self.device.destroy_device(None);
            if let Some((loader, m)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(m, None);
            }
            self.instance.destroy_instance(None);
        }
        // Leaks are reported at vkDestroyDevice: check after it.
        let problems = self.validation_problems();
        assert!(problems.is_empty(), "the validation layer reported {} problem(s):\n{}", problems.len(), problems.join("\n"));
    }
}

fn range(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange { aspect_mask: aspect, base_mip_level: 0, level_count: 1, base_array_layer: 0, layer_count: 1 }
}

fn copy_region(img: &HostImage) -> vk::BufferImageCopy {
    vk::BufferImageCopy {
        buffer_offset: 0,
        buffer_row_length: 0,
        buffer_image_height: 0,
        image_subresource: vk::ImageSubresourceLayers {
            aspect_mask: img.aspect,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        },
        image_offset: vk::Offset3D::default(),
        image_extent: vk::Extent3D { width: img.width, height: img.height, depth: 1 },
    }
}

/// Bytes per texel of the formats the tests use.
pub fn texel_size(format: vk::Format) -> usize {
    match format {
        vk::Format::R8_UNORM => 1,
        vk::Format::R16_SFLOAT | vk::Format::R16_UNORM | vk::Format::D16_UNORM | vk::Format::R8G8_UNORM => 2,
        vk::Format::R32_SFLOAT
        | vk::Format::R32_UINT
        | vk::Format::D32_SFLOAT
        | vk::Format::R8G8B8A8_UNORM
        | vk::Format::R16G16_SFLOAT
        | vk::Format::A2B10G10R10_UNORM_PACK32 => 4,
        vk::Format::R16G16B16A16_SFLOAT | vk::Format::R32G32_SFLOAT => 8,
        vk::Format::R32G32B32A32_SFLOAT | vk::Format::R32G32B32A32_UINT => 16,
        f => panic!("texel_size: add {f:?}"),
    }
}
