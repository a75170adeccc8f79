/*
 * hybrid-rt from C: a checked tour of every entry point (samples/c/ao.c is the page-long
 * integration; start there).
 *
 * The engine (engine.c) creates its own Vulkan instance and device (enabling what the SDK asks
 * for); this program registers a ground quad and a small ceiling quad with the SDK, fills a
 * 32x32 G-buffer (a camera looking straight down at the ground: constant depth, normals +Y),
 * records the SDK's BVH and AO work into its own command buffer, submits it, waits on its
 * own fence and hands the ticket back. Then it checks the AO: dark under the ceiling, open
 * elsewhere, open everywhere once the ceiling instance is removed; shadows, GI, mirrors,
 * injection, denoising and the debug views; and that bad input gets the right status codes.
 * Exit code 0 = all checks passed. With the Khronos validation layer installed, any
 * validation error fails the run.
 */
#include "engine.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The timings of run_frame's last ticket, and of its tasks' passes (the context times them:
 * HrtInitSettings.time_passes). */
static HrtTaskTiming timings[8];
static HrtPassTiming passes[16];
static uint32_t pass_count = 0;

/* Records the container between two full barriers (the engine's own work around it), submits,
 * waits, hands the ticket back and returns the number of timed tasks. */
static uint32_t run_frame(HrtContext *ctx, HrtTaskContainer *frame, Image *out, uint32_t texel_bytes, float *result) {
    VkCommandBuffer cmd = begin();
    HrtTicket ticket;
    CHECK_HRT(hrt_build_gpu_task(ctx, frame, cmd, &ticket));
    uint32_t in_flight = 0;
    CHECK_HRT(hrt_tickets_in_flight(ctx, NULL, 0, &in_flight));
    EXPECT(in_flight == 1, "one ticket in flight (%u)", in_flight);
    EXPECT(hrt_task_container_len(frame) == 0, "a built container is emptied");
    Buffer readback = record_readback(cmd, out, VK_IMAGE_LAYOUT_GENERAL, texel_bytes);
    submit_and_wait(cmd);

    uint32_t count = 0;
    CHECK_HRT(hrt_mark_gpu_task_completed_with_passes(ctx, ticket, timings, 8, &count, passes, 16, &pass_count));
    for (uint32_t i = 0; i < count && i < 8; i++)
        printf("  task %u (kind %u, \"%s\"): %.3f ms\n", timings[i].task_index, timings[i].kind, timings[i].label,
               timings[i].gpu_ms);
    for (uint32_t i = 0; i < pass_count && i < 16; i++)
        printf("    pass %s of task %u: %.3f ms\n", passes[i].pass, passes[i].task_index, passes[i].gpu_ms);
    /* The same ticket twice is refused. */
    EXPECT(hrt_mark_gpu_task_completed(ctx, ticket, NULL, 0, NULL) == HRT_ERROR_UNKNOWN_TICKET, "second return");

    read_and_free(readback, (size_t)W * H * texel_bytes, result);
    return count;
}

int main(void) {
    engine_create();

    /* ---- The SDK context. */
    hrt_set_log_callback(log_sdk_message, HRT_LOG_WARNING, NULL);
    HrtContextDesc desc;
    memset(&desc, 0, sizeof desc);
    desc.api_version = HRT_API_VERSION;
    desc.get_instance_proc_addr = (const void *)vkGetInstanceProcAddr;
    desc.instance = instance;
    desc.physical_device = physical_device;
    desc.device = device;
    desc.enabled_extensions = device_extensions;
    desc.enabled_extension_count = device_extension_count;
    desc.instance_api_version = VK_API_VERSION_1_3;
    desc.enabled_features = &device_features;
    desc.debug_utils = validation; /* the instance enables VK_EXT_debug_utils with validation */
    desc.settings = hrt_init_settings_default();
    EXPECT(!desc.settings.time_passes, "passes are not timed by default");
    desc.settings.time_passes = true;
    HrtContext *ctx = NULL;
    desc.api_version = HRT_API_VERSION + 1;
    EXPECT(hrt_context_create(&desc, &ctx) == HRT_ERROR_VERSION_MISMATCH, "a header/library mismatch is refused");
    desc.api_version = HRT_API_VERSION;
    desc.enabled_features = NULL;
    EXPECT(hrt_context_create(&desc, &ctx) == HRT_ERROR_MISSING_DEVICE_SUPPORT && !ctx, "no feature chain: refused, named");
    desc.enabled_features = &device_features;
    desc.instance_api_version = VK_API_VERSION_1_2;
    EXPECT(hrt_context_create(&desc, &ctx) == HRT_ERROR_MISSING_DEVICE_SUPPORT && !ctx, "a 1.2 instance is refused");
    desc.instance_api_version = VK_API_VERSION_1_3;
    CHECK_HRT(hrt_context_create(&desc, &ctx));
    char device_name[256];
    hrt_device_name(ctx, device_name, sizeof device_name);
    printf("hybrid-rt on %s\n", device_name);

    /* ---- Geometry: a 20x20 ground quad at y = 0 and a 1x1 ceiling quad 0.2 above it. The
     * ground is tightly packed with 32-bit indices; the ceiling is held as engines often hold
     * meshes: interleaved 24-byte vertices (uv, then the position at byte 12, then padding),
     * 16-bit indices 2 bytes into a shared index buffer, modelled at y = 0 and lifted by its
     * part transform. The SDK keeps the same compact copy either way. */
    const float ground[] = {-10, 0, -10, 10, 0, -10, 10, 0, 10, -10, 0, 10};
    const float ceiling[] = {0, 0, 0, -0.5f, 0, -0.5f, 1, 0, 0, 0.5f, 0, -0.5f, 1, 1, 0, 0.5f, 0, 0.5f, 0, 1, 0, -0.5f, 0, 0.5f};
    const uint32_t quad_indices[] = {0, 2, 1, 0, 3, 2};
    const uint16_t shared_indices[] = {0xffff, 0, 2, 1, 0, 3, 2};
    Buffer vb_ground = make_buffer(sizeof ground, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, ground);
    Buffer vb_ceiling = make_buffer(sizeof ceiling, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, ceiling);
    Buffer ib = make_buffer(sizeof quad_indices, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, quad_indices);
    Buffer ib16 = make_buffer(sizeof shared_indices, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, shared_indices);

    HrtGeometryHandle geometries[2];
    HrtInstanceHandle instances[2];
    CHECK_HRT(hrt_create_geometry_handles(ctx, 2, geometries));
    CHECK_HRT(hrt_create_instance_handles(ctx, 2, instances));
    HrtTaskContainer *frame = NULL;
    CHECK_HRT(hrt_task_container_create(ctx, &frame));
    EXPECT(hrt_task_container_set_task_label(frame, "nothing yet") == HRT_ERROR_INVALID_INPUT, "no task to label");

    Buffer vbs[2] = {vb_ground, vb_ceiling};
    for (int i = 0; i < 2; i++) {
        HrtGeometryTask g = hrt_geometry_task_default();
        g.handle = geometries[i];
        g.input.vertices.buffer = vbs[i].buffer;
        g.input.vertices.count = 4;
        g.input.indices.buffer = ib.buffer;
        g.input.indices.count = 6;
        if (i == 1) {
            g.input.vertices.offset = 12;
            g.input.vertices.stride = 24;
            g.input.indices.buffer = ib16.buffer;
            g.input.indices.offset = 2;
            g.input.indices.format = VK_FORMAT_R16_UINT;
            g.input.has_transform = true;
            const float lift[12] = {1, 0, 0, 0, 0, 1, 0, 0.2f, 0, 0, 1, 0}; /* row-major 3x4 */
            memcpy(g.input.transform, lift, sizeof lift);
            g.input.build_hint = HRT_BUILD_HINT_PREFER_FAST_TRACE;
            CHECK_HRT(hrt_set_geometry_name(ctx, geometries[i], "ceiling"));
        }
        CHECK_HRT(hrt_schedule_geometry(frame, &g));
        HrtInstanceTask inst = hrt_instance_task_default();
        inst.handle = instances[i];
        inst.input.geometry = geometries[i];
        inst.input.initial_tile_color[0] = 1.0f; /* magenta: "not injected yet" */
        inst.input.initial_tile_color[2] = 1.0f;
        CHECK_HRT(hrt_schedule_instance(frame, &inst));
    }
    HrtBvhBuildTask bvh = hrt_bvh_build_task_default();
    /* Frames that only move instances may refit the TLAS (up to 4 in a row); adding or
     * removing one, as below, rebuilds it. */
    EXPECT(bvh.tlas_max_refits == 0, "rebuilt every frame by default");
    bvh.tlas_max_refits = 4;
    CHECK_HRT(hrt_schedule_bvh_build(frame, &bvh));

    /* ---- Bad input gets a status, and schedules nothing. */
    HrtInstanceTask bad = hrt_instance_task_default();
    bad.handle = instances[0];
    bad.input.geometry = geometries[0];
    bad.input.transform[3] = NAN;
    EXPECT(hrt_schedule_instance(frame, &bad) == HRT_ERROR_INVALID_TRANSFORM, "NaN transform");
    bad.input.transform[3] = 0.0f;
    bad.operation = 7;
    EXPECT(hrt_schedule_instance(frame, &bad) == HRT_ERROR_INVALID_INPUT, "out-of-range enum");
    EXPECT(hrt_schedule_instance(NULL, &bad) == HRT_ERROR_NULL_POINTER, "NULL container");
    EXPECT(hrt_schedule_instance(frame, NULL) == HRT_ERROR_NULL_POINTER, "NULL task");
    HrtGeometryTask stale = hrt_geometry_task_default();
    stale.handle = geometries[0] + (1ull << 32); /* same slot, another generation: stale */
    stale.input.vertices.buffer = vb_ground.buffer;
    stale.input.vertices.count = 3;
    EXPECT(hrt_schedule_geometry(frame, &stale) == HRT_ERROR_INVALID_HANDLE, "stale handle");
    char message[256];
    hrt_last_error_message(message, sizeof message);
    printf("refused as expected: %s\n", message);

    /* ---- The G-buffer: a camera 3 above the origin looking straight down (-Y). */
    const float eye_height = 3.0f, near = 0.05f, far = 100.0f, fov = 60.0f * 3.14159265f / 180.0f;
    const float f = 1.0f / tanf(fov / 2.0f);
    HrtCamera camera = {
        /* world_to_view, column-major: x_v = x, y_v = -z, z_v = y - 3 */
        {1, 0, 0, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 0, -eye_height, 1},
        /* Vulkan perspective: y down, depth 0..1 */
        {f, 0, 0, 0, 0, -f, 0, 0, 0, 0, far / (near - far), -1, 0, 0, near * far / (near - far), 0},
    };
    const float z_view = -eye_height;
    const float ground_depth = (far / (near - far) * z_view + near * far / (near - far)) / -z_view;

    Image depth = make_image(VK_FORMAT_R32_SFLOAT, VK_IMAGE_USAGE_SAMPLED_BIT);
    Image normals = make_image(VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_USAGE_SAMPLED_BIT);
    Image out = make_image(VK_FORMAT_R32_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT);
    VkCommandBuffer cmd = begin();
    VkImageSubresourceRange all = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    VkClearColorValue depth_value = {{ground_depth, 0, 0, 0}};
    VkClearColorValue up = {{0, 1, 0, 0}};
    VkClearColorValue zero = {{0, 0, 0, 0}};
    transition(cmd, depth.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    transition(cmd, normals.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    transition(cmd, out.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    vkCmdClearColorImage(cmd, depth.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &depth_value, 1, &all);
    vkCmdClearColorImage(cmd, normals.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &up, 1, &all);
    vkCmdClearColorImage(cmd, out.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &zero, 1, &all);
    transition(cmd, depth.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    transition(cmd, normals.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    transition(cmd, out.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_GENERAL);
    submit_and_wait(cmd);

    HrtTraceAmbientOcclusionTask ao = hrt_trace_ambient_occlusion_task_default();
    ao.common.depth.image = sdk_image(&depth, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    ao.common.normals.image = sdk_image(&normals, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    ao.common.normals.normal_type = HRT_NORMAL_RGB_VECTOR;
    ao.common.viewport.width = W;
    ao.common.viewport.height = H;
    ao.common.camera = camera;
    ao.common.use_inline_rt = hrt_supports_inline_rt(ctx);
    ao.output = sdk_image(&out, VK_IMAGE_LAYOUT_GENERAL);
    ao.ray_length = 1.0f;
    ao.rays_per_pixel = 16;
    CHECK_HRT(hrt_schedule_ambient_occlusion(frame, &ao));
    EXPECT(hrt_task_container_set_task_label(frame, NULL) == HRT_ERROR_NULL_POINTER, "a NULL label");
    CHECK_HRT(hrt_task_container_set_task_label(frame, "ao: under the ceiling"));

    /* ---- Frame 1: everything registered; dark under the ceiling, open at the corners. */
    float result[W * H];
    printf("frame 1:\n");
    uint32_t timed = run_frame(ctx, frame, &out, 4, result);
    EXPECT(timed >= 2, "BVH and AO timings reported (%u)", timed);
    int labelled = 0;
    for (uint32_t i = 0; i < timed && i < 8; i++)
        if (timings[i].kind == HRT_TASK_AMBIENT_OCCLUSION)
            labelled = strcmp(timings[i].label, "ao: under the ceiling") == 0;
    EXPECT(labelled, "the AO timing carries the task's label");
    EXPECT(hrt_tlas_instance_count(ctx) == 2, "two instances in the TLAS");
    float centre = result[(H / 2) * W + W / 2], corner = result[0];
    printf("AO under the ceiling %.3f, at the corner %.3f\n", centre, corner);
    EXPECT(centre < 0.6f, "the ceiling occludes the centre (%f)", centre);
    EXPECT(corner > 0.999f, "nothing occludes the corner (%f)", corner);

    /* ---- The rays' random numbers: blue noise (or white) for image-quality comparisons
     * traces the same occlusion; a value outside HrtRandomNumbers is refused. */
    {
        HrtTraceAmbientOcclusionTask blue = ao;
        blue.common.random_numbers = HRT_RANDOM_NUMBERS_BLUE_NOISE;
        CHECK_HRT(hrt_schedule_ambient_occlusion(frame, &blue));
        float blue_result[W * H];
        run_frame(ctx, frame, &out, 4, blue_result);
        float c = blue_result[(H / 2) * W + W / 2];
        EXPECT(c < 0.6f && blue_result[0] > 0.999f, "blue noise: occluded centre %f, open corner %f", c, blue_result[0]);
        blue.common.random_numbers = 3;
        EXPECT(hrt_schedule_ambient_occlusion(frame, &blue) == HRT_ERROR_INVALID_INPUT, "an unknown generator");
    }

    /* ---- G-buffer conventions: normals in an engine basis (custom 3x3, here a scaled
     * identity) trace the same; an input mask covering the image leaves AO 1 (background)
     * everywhere; a roughness remap with min > max is refused. */
    {
        HrtTraceAmbientOcclusionTask custom = ao;
        custom.common.normals.space = HRT_NORMAL_SPACE_CUSTOM;
        const float twice[9] = {2, 0, 0, 0, 2, 0, 0, 0, 2};
        memcpy(custom.common.normals.normal_to_world, twice, sizeof twice);
        CHECK_HRT(hrt_schedule_ambient_occlusion(frame, &custom));
        float custom_result[W * H];
        run_frame(ctx, frame, &out, 4, custom_result);
        float c = custom_result[(H / 2) * W + W / 2];
        EXPECT(c < 0.6f, "custom-space normals: the ceiling still occludes the centre (%f)", c);

        /* Any colour format a float sampler reads is a mask: here an sRGB colour image. */
        Image mask = filled_image(VK_FORMAT_R8G8B8A8_SRGB, 1, 0, 0, 1);
        HrtTraceAmbientOcclusionTask masked = ao;
        masked.common.input_mask = sdk_image(&mask, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
        HrtTraceAmbientOcclusionTask integer_mask = masked;
        integer_mask.common.input_mask.format = VK_FORMAT_R8_UINT;
        EXPECT(hrt_schedule_ambient_occlusion(frame, &integer_mask) == HRT_ERROR_UNSUPPORTED_FORMAT, "an integer mask format is refused");
        CHECK_HRT(hrt_schedule_ambient_occlusion(frame, &masked));
        float masked_result[W * H];
        run_frame(ctx, frame, &out, 4, masked_result);
        float m = masked_result[(H / 2) * W + W / 2];
        EXPECT(m == 1.0f, "a masked pixel is background: AO 1 (%f)", m);
        free_image(mask);

        HrtTraceSpecularTask remap = hrt_trace_specular_task_default();
        remap.common = ao.common;
        remap.common.roughness.min_roughness = 0.6f;
        remap.common.roughness.max_roughness = 0.4f;
        remap.output = ao.output;
        EXPECT(hrt_schedule_specular(frame, &remap) == HRT_ERROR_INVALID_INPUT, "min_roughness > max_roughness is refused");
    }

    /* ---- A named geometry is named in errors: registering the ceiling again is refused when
     * the container is built, and the message quotes its name. */
    {
        HrtGeometryTask again = hrt_geometry_task_default();
        again.handle = geometries[1];
        again.input.vertices.buffer = vb_ground.buffer;
        again.input.vertices.count = 4;
        again.input.indices.buffer = ib.buffer;
        again.input.indices.count = 6;
        CHECK_HRT(hrt_schedule_geometry(frame, &again));
        VkCommandBuffer cmd = begin();
        HrtTicket unused;
        EXPECT(hrt_build_gpu_task(ctx, frame, cmd, &unused) == HRT_ERROR_INVALID_HANDLE, "registered twice");
        char why[256];
        hrt_last_error_message(why, sizeof why);
        EXPECT(strstr(why, "\"ceiling\"") != NULL, "the error names the geometry: %s", why);
        submit_and_wait(cmd);
        hrt_task_container_clear(frame);
        HrtGeometryComponent part = hrt_geometry_component_default();
        EXPECT(!part.has_transform && !part.has_vertex_range, "a default part: identity, all vertices");
    }

    /* ---- The ticket contract: a ticket handed back before its command buffer ran is refused
     * (and stays in flight), and the context is not destroyed under the GPU. */
    {
        ao.rays_per_pixel = 2;
        CHECK_HRT(hrt_schedule_ambient_occlusion(frame, &ao));
        VkCommandBuffer early_cmd = begin();
        HrtTicket early;
        CHECK_HRT(hrt_build_gpu_task(ctx, frame, early_cmd, &early));
        EXPECT(hrt_mark_gpu_task_completed(ctx, early, NULL, 0, NULL) == HRT_ERROR_TICKET_NOT_COMPLETE, "not submitted yet");
        EXPECT(hrt_context_destroy(ctx) == HRT_ERROR_TICKETS_IN_FLIGHT, "not destroyed while the GPU may run a ticket");
        uint32_t unfinished = 0;
        CHECK_HRT(hrt_unfinished_tickets(ctx, NULL, 0, &unfinished));
        EXPECT(unfinished == 1, "one unfinished ticket (%u)", unfinished);
        submit_and_wait(early_cmd);
        CHECK_HRT(hrt_unfinished_tickets(ctx, NULL, 0, &unfinished));
        EXPECT(unfinished == 0, "the GPU ran it");
        CHECK_HRT(hrt_mark_gpu_task_completed(ctx, early, NULL, 0, NULL));
        /* A frame index replays a frame's noise exactly (2 rays per pixel: noisy). */
        static float replay[2][W * H];
        for (int k = 0; k < 2; k++) {
            CHECK_HRT(hrt_task_container_set_frame_index(frame, 9));
            CHECK_HRT(hrt_schedule_ambient_occlusion(frame, &ao));
            run_frame(ctx, frame, &out, 4, replay[k]);
        }
        EXPECT(memcmp(replay[0], replay[1], sizeof replay[0]) == 0, "frame 9 twice: the same image");
        ao.rays_per_pixel = 16;
    }

    HrtResourceAllocations mem;
    CHECK_HRT(hrt_resource_allocations(ctx, &mem));
    EXPECT(mem.blas.count == 2, "two BLASes");
    EXPECT(hrt_destroy_geometry_handles(ctx, &geometries[1], 1) == HRT_ERROR_GEOMETRY_IN_USE, "geometry in use");

    /* ---- Shadows: a light straight above; the ceiling shadows the centre, not the corner. */
    Image shadow = make_image(VK_FORMAT_R32G32_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT);
    cmd = begin();
    transition(cmd, shadow.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
    submit_and_wait(cmd);
    HrtTraceShadowTask shadow_task = hrt_trace_shadow_task_default();
    shadow_task.common = ao.common;
    shadow_task.light.light_type = HRT_LIGHT_POINT;
    shadow_task.light.position[1] = 2.0f;
    shadow_task.output = sdk_image(&shadow, VK_IMAGE_LAYOUT_GENERAL);
    EXPECT(isinf(shadow_task.max_ray_length), "shadow rays are not capped by default");
    HrtTraceShadowTask uncapped = shadow_task;
    uncapped.max_ray_length = 0.0f;
    EXPECT(hrt_schedule_shadow(frame, &uncapped) == HRT_ERROR_INVALID_INPUT, "a zero max_ray_length is refused");
    CHECK_HRT(hrt_schedule_shadow(frame, &shadow_task));
    float rg[W * H * 2];
    printf("shadow frame:\n");
    run_frame(ctx, frame, &shadow, 8, rg);
    const float *sc = &rg[((H / 2) * W + W / 2) * 2];
    printf("shadow at the centre: distance %.3f, visible %.2f; corner %.3f\n", sc[0], sc[1], rg[0]);
    EXPECT(sc[0] > 0.1f && sc[0] < 0.3f && sc[1] == 0.0f, "the ceiling 0.2 above shadows the centre");
    EXPECT(rg[0] < 0.0f && rg[1] == 1.0f, "the corner sees the light");
    free_image(shadow);

    /* ---- Denoised shadows: a denoising context owns the history; the trace task's output
     * image is the denoise task's input in the same container (the SDK orders the two). */
    HrtDenoisingContextInput dci_in = hrt_denoising_context_input_default();
    dci_in.max_width = W;
    dci_in.max_height = H;
    dci_in.signal = 99;
    HrtDenoisingContextHandle denoiser = 0;
    EXPECT(hrt_create_denoising_context(ctx, &dci_in, &denoiser) == HRT_ERROR_INVALID_INPUT, "out-of-range signal type");
    dci_in.signal = HRT_SIGNAL_SHADOW;
    /* The main camera's view: its contexts share one denoiser guide, and so one size. */
    EXPECT(dci_in.view_id == 0, "no view by default");
    dci_in.view_id = 1;
    CHECK_HRT(hrt_create_denoising_context(ctx, &dci_in, &denoiser));
    HrtDenoisingContextInput other_size = dci_in;
    other_size.max_width = W / 2;
    HrtDenoisingContextHandle refused = 0;
    EXPECT(hrt_create_denoising_context(ctx, &other_size, &refused) == HRT_ERROR_INVALID_INPUT,
           "a second size in one view");
    Image noisy = make_image(VK_FORMAT_R32G32_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_SAMPLED_BIT);
    Image clean = make_image(VK_FORMAT_R32_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT);
    cmd = begin();
    transition(cmd, noisy.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
    transition(cmd, clean.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
    submit_and_wait(cmd);
    shadow_task.output = sdk_image(&noisy, VK_IMAGE_LAYOUT_GENERAL);
    HrtDenoiseShadowTask denoise = hrt_denoise_shadow_task_default();
    denoise.context = denoiser;
    denoise.common.depth = ao.common.depth;
    denoise.common.normals = ao.common.normals;
    denoise.common.viewport = ao.common.viewport;
    denoise.common.camera = ao.common.camera;
    denoise.light = shadow_task.light;
    denoise.input = sdk_image(&noisy, VK_IMAGE_LAYOUT_GENERAL);
    denoise.output = sdk_image(&clean, VK_IMAGE_LAYOUT_GENERAL);
    float vis_px[W * H];
    for (int f = 0; f < 4; f++) {
        CHECK_HRT(hrt_schedule_shadow(frame, &shadow_task));
        CHECK_HRT(hrt_schedule_denoise_shadow(frame, &denoise));
        printf("denoised shadow frame %d:\n", f);
        run_frame(ctx, frame, &clean, 4, vis_px);
    }
    printf("denoised visibility: centre %.3f, corner %.3f\n", vis_px[(H / 2) * W + W / 2], vis_px[0]);
    /* The shadow denoiser's three passes, timed inside its task (task 1, after the trace). */
    static const char *shadow_passes[3] = {"shadow_prep", "shadow_blur", "shadow_temporal"};
    EXPECT(pass_count == 3, "the shadow denoiser's passes are timed (%u)", pass_count);
    for (uint32_t i = 0; i < pass_count && i < 3; i++)
        EXPECT(passes[i].kind == HRT_TASK_DENOISE_SHADOW && passes[i].task_index == 1 &&
                   strcmp(passes[i].pass, shadow_passes[i]) == 0 && passes[i].gpu_ms >= 0.0,
               "pass %u is %s of the denoise task", i, shadow_passes[i]);
    EXPECT(vis_px[(H / 2) * W + W / 2] == 0.0f && vis_px[0] == 1.0f, "a hard light's shadow stays exact");
    HrtDenoiseTask wrong = hrt_denoise_task_default();
    wrong.context = denoiser;
    wrong.common = denoise.common;
    wrong.input = wrong.output = sdk_image(&clean, VK_IMAGE_LAYOUT_GENERAL);
    EXPECT(hrt_schedule_denoise_diffuse(frame, &wrong) == HRT_ERROR_INVALID_INPUT, "an image without SAMPLED usage is no input");
    wrong.input = sdk_image(&noisy, VK_IMAGE_LAYOUT_GENERAL);
    EXPECT(hrt_schedule_denoise_diffuse(frame, &wrong) == HRT_ERROR_UNSUPPORTED_FORMAT, "a two-channel image is no diffuse input");
    /* AO near moving objects: half the AO trace's ray length suits its default falloff. */
    EXPECT(denoise.common.settings.moving_object_reach == 0.5f, "the reach defaults to half the AO trace's default ray length");
    HrtDenoiseShadowTask reaching = denoise;
    reaching.common.settings.moving_object_reach = -1.0f;
    EXPECT(hrt_schedule_denoise_shadow(frame, &reaching) == HRT_ERROR_INVALID_INPUT, "a negative moving-object reach");
    /* Extra blur taps where diffuse history is fresh: off by default, at most 32. */
    EXPECT(denoise.common.settings.fresh_history_taps == 0, "fresh-history taps are off by default");
    HrtDenoiseShadowTask tapping = denoise;
    tapping.common.settings.fresh_history_taps = 33;
    EXPECT(hrt_schedule_denoise_shadow(frame, &tapping) == HRT_ERROR_INVALID_INPUT, "more than 32 fresh-history taps");
    /* A denoise task's G-buffer errors name the struct the engine filled. */
    HrtDenoiseShadowTask remap = denoise;
    remap.common.roughness.min_roughness = 0.5f;
    remap.common.roughness.max_roughness = 0.4f;
    EXPECT(hrt_schedule_denoise_shadow(frame, &remap) == HRT_ERROR_INVALID_INPUT, "a roughness remap with min above max");
    char remap_why[256];
    hrt_last_error_message(remap_why, sizeof remap_why);
    EXPECT(strstr(remap_why, "DenoisingCommon.roughness") != NULL, "the error names DenoisingCommon: %s", remap_why);
    CHECK_HRT(hrt_destroy_denoising_context(ctx, denoiser));
    EXPECT(hrt_destroy_denoising_context(ctx, denoiser) == HRT_ERROR_INVALID_HANDLE, "destroyed twice");
    /* Or all of a context's at once (level unload). */
    HrtDenoisingContextHandle spare;
    CHECK_HRT(hrt_create_denoising_context(ctx, &dci_in, &spare));
    CHECK_HRT(hrt_destroy_all_denoising_context_handles(ctx));
    EXPECT(hrt_destroy_denoising_context(ctx, spare) == HRT_ERROR_INVALID_HANDLE, "destroyed by destroy-all");
    free_image(noisy);
    free_image(clean);

    /* ---- Many lights by resampling: a many-lights context holds the light list (on the GPU)
     * and the view's reservoirs; the task gives the list once and changes it by ranges. */
    HrtManyLightsContextInput mli = hrt_many_lights_context_input_default();
    mli.max_width = W;
    mli.max_height = H;
    mli.max_lights = 2;
    HrtManyLightsContextHandle many_ctx = 0;
    CHECK_HRT(hrt_create_many_lights_context(ctx, &mli, &many_ctx));
    HrtLightInfo ml_lights[2] = {shadow_task.light, shadow_task.light};
    ml_lights[1].intensity = 0.0f; /* switched off: its samples die */
    Image ml_diffuse = make_image(VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT);
    Image ml_specular = make_image(VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT);
    cmd = begin();
    transition(cmd, ml_diffuse.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
    transition(cmd, ml_specular.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
    submit_and_wait(cmd);
    HrtTraceManyLightsTask ml = hrt_trace_many_lights_task_default();
    ml.context = many_ctx;
    ml.common = shadow_task.common;
    ml.light_operation = HRT_LIGHT_LIST_WRITE; /* lights 1 and 2 of an empty list: refused at build */
    ml.first_light = 1;
    ml.lights = ml_lights;
    ml.light_count = 2;
    ml.diffuse_output = sdk_image(&ml_diffuse, VK_IMAGE_LAYOUT_GENERAL);
    ml.specular_output = sdk_image(&ml_specular, VK_IMAGE_LAYOUT_GENERAL);
    EXPECT(ml.settings.mode == HRT_RESAMPLING_BIASED && ml.settings.initial_candidates == 8, "the defaults");
    CHECK_HRT(hrt_schedule_many_lights(frame, &ml));
    cmd = begin();
    HrtTicket too_many;
    EXPECT(hrt_build_gpu_task(ctx, frame, cmd, &too_many) == HRT_ERROR_INVALID_INPUT, "a write past the list's end");
    submit_and_wait(cmd);
    hrt_task_container_clear(frame);
    ml.light_operation = HRT_LIGHT_LIST_REPLACE;
    ml.first_light = 0;
    CHECK_HRT(hrt_schedule_many_lights(frame, &ml));
    float ml_px[W * H * 4];
    printf("many lights frame:\n");
    run_frame(ctx, frame, &ml_diffuse, 16, ml_px);
    const float *mc = &ml_px[((H / 2) * W + W / 2) * 4];
    printf("many lights, diffuse: centre %.4f, corner %.4f\n", mc[0], ml_px[0]);
    EXPECT(mc[0] == 0.0f && ml_px[0] > 0.0f, "the ceiling shadows the centre; the corner is lit");
    CHECK_HRT(hrt_destroy_many_lights_context(ctx, many_ctx));
    EXPECT(hrt_destroy_many_lights_context(ctx, many_ctx) == HRT_ERROR_INVALID_HANDLE, "destroyed twice");
    free_image(ml_diffuse);
    free_image(ml_specular);

    /* ---- Two lights in one pass: the same light twice gives the same visibility twice. */
    Image vis = make_image(VK_FORMAT_R32_UINT, VK_IMAGE_USAGE_STORAGE_BIT);
    Image packed = make_image(VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT);
    cmd = begin();
    transition(cmd, vis.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
    transition(cmd, packed.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
    submit_and_wait(cmd);
    HrtLightInfo two[2] = {shadow_task.light, shadow_task.light};
    two[1].position[0] = 50.0f; /* far to the side: the ceiling does not shadow the centre */
    two[1].position[1] = 0.5f;
    HrtTraceMultiShadowTask multi = hrt_trace_multi_shadow_task_default();
    multi.common = ao.common;
    multi.lights = two;
    multi.light_count = 2;
    multi.visibility = sdk_image(&vis, VK_IMAGE_LAYOUT_GENERAL);
    multi.packed = sdk_image(&packed, VK_IMAGE_LAYOUT_GENERAL);
    /* Light 1 on its own too, in the single-light format (for a DenoiseShadow task). */
    Image light1 = make_image(VK_FORMAT_R32G32_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT);
    cmd = begin();
    transition(cmd, light1.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
    submit_and_wait(cmd);
    multi.light_outputs[0].light = 1;
    multi.light_outputs[0].output = sdk_image(&light1, VK_IMAGE_LAYOUT_GENERAL);
    multi.light_output_count = 1;
    CHECK_HRT(hrt_schedule_multi_shadow(frame, &multi));
    uint32_t words[W * H];
    printf("multi-shadow frame:\n");
    run_frame(ctx, frame, &vis, 4, (float *)words);
    uint32_t centre_word = words[(H / 2) * W + W / 2];
    printf("visibility at the centre: light 0 %u/255, light 1 %u/255\n", centre_word & 255u, (centre_word >> 8) & 255u);
    EXPECT((centre_word & 255u) == 0u && ((centre_word >> 8) & 255u) == 255u, "light 0 blocked, light 1 visible");
    float light1_px[W * H * 2];
    run_frame(ctx, frame, &light1, 8, light1_px);
    const float *c1 = &light1_px[((H / 2) * W + W / 2) * 2];
    EXPECT(c1[0] < 0.0f && c1[1] == 1.0f, "light 1's own output: visible at the centre (%f, %f)", c1[0], c1[1]);
    /* Limits: 33 lights, 5 per-light outputs, a spot with its inner cone wider than its outer. */
    static HrtLightInfo many[33];
    for (int i = 0; i < 33; i++) many[i] = two[1];
    HrtTraceMultiShadowTask bad_multi = multi;
    bad_multi.lights = many;
    bad_multi.light_count = 33;
    EXPECT(hrt_schedule_multi_shadow(frame, &bad_multi) == HRT_ERROR_INVALID_INPUT, "33 lights are refused (HRT_MAX_SHADOW_LIGHTS %u)", HRT_MAX_SHADOW_LIGHTS);
    bad_multi = multi;
    bad_multi.light_output_count = HRT_MAX_LIGHT_OUTPUTS + 1;
    EXPECT(hrt_schedule_multi_shadow(frame, &bad_multi) == HRT_ERROR_INVALID_INPUT, "too many per-light outputs");
    HrtLightInfo spot = two[1];
    spot.light_type = HRT_LIGHT_SPOT;
    spot.inner_cone = 0.7f;
    spot.outer_cone = 0.6f;
    bad_multi = multi;
    bad_multi.lights = &spot;
    bad_multi.light_count = 1;
    bad_multi.light_output_count = 0;
    EXPECT(hrt_schedule_multi_shadow(frame, &bad_multi) == HRT_ERROR_INVALID_INPUT, "a spot's inner cone wider than its outer");
    free_image(light1);
    free_image(vis);
    free_image(packed);

    /* ---- Diffuse GI under a constant sky: the open corner sees the sky's radiance. */
    Image gi = make_image(VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT);
    cmd = begin();
    transition(cmd, gi.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
    submit_and_wait(cmd);
    HrtTraceDiffuseTask diffuse = hrt_trace_diffuse_task_default();
    diffuse.common = ao.common;
    diffuse.output = sdk_image(&gi, VK_IMAGE_LAYOUT_GENERAL);
    diffuse.rays_per_pixel = 8;
    diffuse.ray_length = 1.0f;
    diffuse.miss_radiance[0] = diffuse.miss_radiance[1] = diffuse.miss_radiance[2] = 0.5f;
    CHECK_HRT(hrt_schedule_diffuse(frame, &diffuse));
    float gi_px[W * H * 4];
    printf("diffuse frame:\n");
    run_frame(ctx, frame, &gi, 16, gi_px);
    printf("diffuse at the corner: %.3f %.3f %.3f\n", gi_px[0], gi_px[1], gi_px[2]);
    EXPECT(fabsf(gi_px[0] - 0.5f) < 1e-4f && fabsf(gi_px[2] - 0.5f) < 1e-4f, "the open corner sees the sky");
    /* An environment map replaces the constant sky: a 1x1 map is the same radiance everywhere. */
    {
        Image sky = filled_image(VK_FORMAT_R16G16B16A16_SFLOAT, 0.25f, 0.5f, 0.75f, 1.0f);
        HrtTraceDiffuseTask with_sky = diffuse;
        with_sky.environment.image = sdk_image(&sky, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
        with_sky.environment.intensity = 2.0f;
        CHECK_HRT(hrt_schedule_diffuse(frame, &with_sky));
        run_frame(ctx, frame, &gi, 16, gi_px);
        printf("diffuse at the corner under the map: %.3f %.3f %.3f\n", gi_px[0], gi_px[1], gi_px[2]);
        EXPECT(fabsf(gi_px[0] - 0.5f) < 1e-3f && fabsf(gi_px[1] - 1.0f) < 1e-3f && fabsf(gi_px[2] - 1.5f) < 1e-3f,
               "the open corner sees the map x 2");
        with_sky.environment.rotation[0] = 2.0f;
        EXPECT(hrt_schedule_diffuse(frame, &with_sky) == HRT_ERROR_INVALID_TRANSFORM, "a scaled rotation is refused");
        free_image(sky);
    }
    free_image(gi);

    /* ---- Specular: a mirror ground reflects the ceiling (its cache: magenta) at the centre
     * and the sky at the corner. */
    Image spec = make_image(VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT);
    cmd = begin();
    transition(cmd, spec.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
    submit_and_wait(cmd);
    HrtTraceSpecularTask mirror = hrt_trace_specular_task_default();
    mirror.common = ao.common;
    mirror.common.roughness.global_roughness = 0.0f;
    mirror.output = sdk_image(&spec, VK_IMAGE_LAYOUT_GENERAL);
    mirror.ray_length = 10.0f;
    mirror.miss_radiance[1] = 0.25f;
    CHECK_HRT(hrt_schedule_specular(frame, &mirror));
    float spec_px[W * H * 4];
    printf("specular frame:\n");
    run_frame(ctx, frame, &spec, 16, spec_px);
    const float *m = &spec_px[((H / 2) * W + W / 2) * 4];
    printf("mirror at the centre: %.3f %.3f %.3f at %.3f; corner %.3f %.3f %.3f\n", m[0], m[1], m[2], m[3], spec_px[0], spec_px[1], spec_px[2]);
    EXPECT(m[0] == 1.0f && m[1] == 0.0f && m[2] == 1.0f && fabsf(m[3] - 0.2f) < 0.01f, "the centre mirrors the ceiling");
    EXPECT(spec_px[0] == 0.0f && spec_px[1] == 0.25f && spec_px[3] == 10.0f, "the corner mirrors the sky");

    /* ---- Relighting: no camera injected the ceiling, so its cache holds magenta. Given the
     * engine's light (a sun straight down, intensity 2, warm) it takes albedo (0.5) x the
     * sun's irradiance on its front face, and the mirror shows that instead. */
    HrtLightInfo sun = hrt_trace_shadow_task_default().light;
    sun.intensity = 2.0f;
    sun.color[0] = 1.0f;
    sun.color[1] = 0.5f;
    sun.color[2] = 0.25f;
    HrtRelightCacheTask relight = hrt_relight_cache_task_default();
    relight.lights = &sun;
    relight.light_count = 1;
    CHECK_HRT(hrt_schedule_cache_relight(frame, &relight));
    CHECK_HRT(hrt_schedule_specular(frame, &mirror));
    printf("relight + specular frame:\n");
    run_frame(ctx, frame, &spec, 16, spec_px);
    printf("mirror at the centre, relit: %.3f %.3f %.3f\n", m[0], m[1], m[2]);
    EXPECT(fabsf(m[0] - 1.0f) < 1e-3f && fabsf(m[1] - 0.5f) < 1e-3f && fabsf(m[2] - 0.25f) < 1e-3f,
           "the mirror shows the relit ceiling: 0.5 x 2 x (1, 0.5, 0.25)");
    relight.light_count = 0;
    EXPECT(hrt_schedule_cache_relight(frame, &relight) == HRT_ERROR_INVALID_INPUT, "a relight without lights is refused");

    /* ---- Hit lighting: the mirror's hit is shaded from the lights instead of the cache. The
     * ceiling glows (emission 0.1, 0.2, 0.3); the sun above lights only its top, and the
     * mirror sees its underside: the hit-lit mirror shows the emission alone. */
    {
        HrtInstanceTask glow = hrt_instance_task_default();
        glow.handle = instances[1];
        glow.operation = HRT_OPERATION_UPDATE;
        glow.input.geometry = geometries[1];
        glow.input.initial_tile_color[0] = 1.0f;
        glow.input.initial_tile_color[2] = 1.0f;
        glow.input.emission[0] = 0.1f;
        glow.input.emission[1] = 0.2f;
        glow.input.emission[2] = 0.3f;
        CHECK_HRT(hrt_schedule_instance(frame, &glow));
        HrtTraceSpecularTask lit = mirror;
        lit.hit_lighting.lights = &sun;
        lit.hit_lighting.light_count = 1;
        lit.hit_lighting.max_roughness = 0.0f;
        lit.hit_lighting.indirect = HRT_HIT_INDIRECT_NONE;
        CHECK_HRT(hrt_schedule_specular(frame, &lit));
        printf("hit-lit specular frame:\n");
        run_frame(ctx, frame, &spec, 16, spec_px);
        printf("hit-lit mirror at the centre: %.3f %.3f %.3f\n", m[0], m[1], m[2]);
        EXPECT(fabsf(m[0] - 0.1f) < 1e-4f && fabsf(m[1] - 0.2f) < 1e-4f && fabsf(m[2] - 0.3f) < 1e-4f,
               "the hit-lit mirror shows the unlit underside's emission");
        HrtTraceSpecularTask bad_lit = lit;
        bad_lit.hit_lighting.gather_rays = HRT_MAX_HIT_GATHER_RAYS + 1;
        EXPECT(hrt_schedule_specular(frame, &bad_lit) == HRT_ERROR_INVALID_INPUT, "too many gather rays are refused");
        bad_lit = lit;
        bad_lit.hit_lighting.lights = NULL;
        EXPECT(hrt_schedule_specular(frame, &bad_lit) == HRT_ERROR_NULL_POINTER, "hit lighting without its lights is refused");
        glow.input.emission[1] = -1.0f;
        EXPECT(hrt_schedule_instance(frame, &glow) == HRT_ERROR_INVALID_INPUT, "a negative emission is refused");
    }
    free_image(spec);

    /* ---- Alpha testing: the ceiling updated into a cut-out whose texture is all holes (alpha
     * 0 < cutoff 0.5; its texture coordinates are the first 8 bytes of its 24-byte vertices):
     * rays pass through it and the centre opens. */
    {
        Image holes = filled_image(VK_FORMAT_R8G8B8A8_UNORM, 1, 1, 1, 0);
        HrtGeometryTask cut = hrt_geometry_task_default();
        cut.handle = geometries[1];
        cut.operation = HRT_OPERATION_UPDATE;
        cut.input.vertices.buffer = vb_ceiling.buffer;
        cut.input.vertices.count = 4;
        cut.input.vertices.offset = 12;
        cut.input.vertices.stride = 24;
        cut.input.indices.buffer = ib16.buffer;
        cut.input.indices.offset = 2;
        cut.input.indices.count = 6;
        cut.input.indices.format = VK_FORMAT_R16_UINT;
        cut.input.has_transform = true;
        const float lift[12] = {1, 0, 0, 0, 0, 1, 0, 0.2f, 0, 0, 1, 0};
        memcpy(cut.input.transform, lift, sizeof lift);
        cut.input.has_uvs = true;
        cut.input.uvs.buffer = vb_ceiling.buffer;
        cut.input.uvs.stride = 24;
        cut.input.uvs.count = 4;
        cut.input.has_alpha_test = true;
        cut.input.alpha_test.texture = sdk_image(&holes, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
        HrtGeometryTask bad_cut = cut;
        bad_cut.input.alpha_test.cutoff = 2.0f;
        EXPECT(hrt_schedule_geometry(frame, &bad_cut) == HRT_ERROR_INVALID_INPUT, "an alpha cutoff above 1 is refused");
        /* What each build hint asks of the driver: static geometry of the default hint builds
         * for fast trace and is compacted; FastThenTrace's first build is a fast one. */
        uint32_t hint_flags = 0;
        CHECK_HRT(hrt_build_hint_flags(HRT_BUILD_HINT_AUTO, false, false, &hint_flags));
        EXPECT(hint_flags == (VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR),
               "Auto on static geometry: fast trace + compaction (%u)", hint_flags);
        CHECK_HRT(hrt_build_hint_flags(HRT_BUILD_HINT_FAST_THEN_TRACE, false, true, &hint_flags));
        EXPECT((hint_flags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR) != 0, "FastThenTrace builds fast first");
        EXPECT(hrt_build_hint_flags(9, false, false, &hint_flags) == HRT_ERROR_INVALID_INPUT, "an unknown hint is refused");
        /* Albedo sources for relighting: an albedo texture needs the texture coordinates; vertex
         * colours need a colour format. */
        HrtGeometryTask tinted = cut;
        tinted.input.has_alpha_test = false;
        tinted.input.has_albedo_texture = true;
        tinted.input.albedo_texture = cut.input.alpha_test.texture;
        tinted.input.has_uvs = false;
        EXPECT(hrt_schedule_geometry(frame, &tinted) == HRT_ERROR_INVALID_INPUT, "an albedo texture without uvs is refused");
        tinted.input.has_uvs = true;
        tinted.input.has_colors = true;
        tinted.input.colors = cut.input.uvs;
        tinted.input.colors.format = VK_FORMAT_R8_UNORM;
        EXPECT(hrt_schedule_geometry(frame, &tinted) == HRT_ERROR_UNSUPPORTED_FORMAT, "vertex colours in R8 are refused");
        CHECK_HRT(hrt_schedule_geometry(frame, &cut));
        CHECK_HRT(hrt_schedule_bvh_build(frame, &bvh));
        CHECK_HRT(hrt_schedule_ambient_occlusion(frame, &ao));
        printf("cut-out ceiling frame:\n");
        run_frame(ctx, frame, &out, 4, result);
        float open = result[(H / 2) * W + W / 2];
        EXPECT(open > 0.999f, "a ceiling that is all holes no longer occludes (%f)", open);
        free_image(holes);
    }

    /* ---- Frame 2: the ceiling instance removed: open everywhere. */
    HrtInstanceTask remove = hrt_instance_task_default();
    remove.handle = instances[1];
    remove.operation = HRT_INSTANCE_REMOVE;
    CHECK_HRT(hrt_schedule_instance(frame, &remove));
    CHECK_HRT(hrt_schedule_bvh_build(frame, &bvh));
    CHECK_HRT(hrt_schedule_ambient_occlusion(frame, &ao));
    printf("frame 2:\n");
    run_frame(ctx, frame, &out, 4, result);
    centre = result[(H / 2) * W + W / 2];
    EXPECT(centre > 0.999f, "the removed ceiling no longer occludes (%f)", centre);

    /* ---- The direct-lighting cache: the ground's cache exists by now (its layout came back
     * with frame 1's ticket and frame 2 allocated it); inject a constant lit image, look at
     * the cache through the debug view, clear it, look again. */
    uint64_t cache_bytes = 0;
    CHECK_HRT(hrt_instance_cache_bytes(ctx, instances[0], &cache_bytes));
    EXPECT(cache_bytes > 0, "the ground has a cache");
    printf("ground cache: %llu bytes\n", (unsigned long long)cache_bytes);
    {
        /* No budget set: every cache is resident, none evicted. */
        HrtCacheReport report;
        uint64_t ceiling_bytes = 0;
        CHECK_HRT(hrt_instance_cache_bytes(ctx, instances[1], &ceiling_bytes));
        CHECK_HRT(hrt_cache_report(ctx, &report));
        printf("caches: %llu bytes resident, %llu evicted\n", (unsigned long long)report.resident_bytes,
               (unsigned long long)report.evicted_bytes);
        EXPECT(report.resident_bytes == cache_bytes + ceiling_bytes && report.budget_bytes == 0 && report.evictions == 0,
               "the cache report sums the instances' caches");
    }
    Image lit = make_image(VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_USAGE_SAMPLED_BIT);
    Image view = make_image(VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT);
    cmd = begin();
    VkClearColorValue lit_colour = {{0.2f, 0.4f, 0.6f, 1.0f}};
    transition(cmd, lit.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    vkCmdClearColorImage(cmd, lit.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &lit_colour, 1, &all);
    transition(cmd, lit.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    transition(cmd, view.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
    submit_and_wait(cmd);

    HrtDirectLightingInjectionTask inject = hrt_direct_lighting_injection_task_default();
    inject.depth.image = ao.common.depth.image;
    inject.lit = sdk_image(&lit, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    inject.viewport = ao.common.viewport;
    inject.camera = camera;
    inject.average_window = 1.0f;
    /* One pixel of every NxN block per frame (1..=16; 1, the default, injects every pixel). */
    inject.injection_resolution_stride = 0;
    EXPECT(hrt_schedule_direct_lighting_injection(frame, &inject) == HRT_ERROR_INVALID_INPUT, "injection stride 0");
    inject.injection_resolution_stride = 1;
    CHECK_HRT(hrt_schedule_direct_lighting_injection(frame, &inject));
    HrtTraceAmbientOcclusionTask debug_view = ao;
    debug_view.common.debug_output = HRT_DEBUG_DIRECT_LIGHTING_CACHE;
    debug_view.output = sdk_image(&view, VK_IMAGE_LAYOUT_GENERAL);
    CHECK_HRT(hrt_schedule_ambient_occlusion(frame, &debug_view));
    float rgba[W * H * 4];
    printf("frame 3 (injection + cache view):\n");
    run_frame(ctx, frame, &view, 16, rgba);
    const float *c = &rgba[((H / 2) * W + W / 2) * 4];
    printf("cache at the centre: %.3f %.3f %.3f\n", c[0], c[1], c[2]);
    EXPECT(fabsf(c[0] - 0.2f) < 1e-4f && fabsf(c[1] - 0.4f) < 1e-4f && fabsf(c[2] - 0.6f) < 1e-4f, "injected colour cached");

    HrtClearCacheTask clear = {instances[0]};
    CHECK_HRT(hrt_schedule_clear_cache(frame, &clear));
    CHECK_HRT(hrt_schedule_ambient_occlusion(frame, &debug_view));
    printf("frame 4 (clear + cache view):\n");
    run_frame(ctx, frame, &view, 16, rgba);
    EXPECT(c[0] == 1.0f && c[1] == 0.0f && c[2] == 1.0f, "cleared to the initial colour (%f %f %f)", c[0], c[1], c[2]);
    /* A transfer is validated like every task: the same instance twice is refused. */
    HrtDirectLightTransferTask transfer = hrt_direct_light_transfer_task_default();
    transfer.source = instances[0];
    transfer.target = instances[0];
    EXPECT(hrt_schedule_direct_light_transfer(frame, &transfer) == HRT_ERROR_INVALID_INPUT, "transfer onto itself");
    free_image(lit);
    free_image(view);

    /* ---- Teardown. */
    EXPECT(hrt_destroy_all_geometry_handles(ctx) == HRT_ERROR_GEOMETRY_IN_USE, "geometries still placed");
    CHECK_HRT(hrt_destroy_all_instance_handles(ctx));
    CHECK_HRT(hrt_destroy_all_geometry_handles(ctx));
    EXPECT(hrt_destroy_geometry_handles(ctx, geometries, 1) == HRT_ERROR_INVALID_HANDLE, "destroyed by destroy-all");
    CHECK_HRT(hrt_release_device_resources_immediately(ctx));
    /* A ticket whose command buffer never finishes, as after a device loss (here: it is never
     * submitted). */
    CHECK_HRT(hrt_schedule_bvh_build(frame, &bvh));
    VkCommandBuffer lost_cmd = begin();
    HrtTicket lost;
    CHECK_HRT(hrt_build_gpu_task(ctx, frame, lost_cmd, &lost));
    EXPECT(vkEndCommandBuffer(lost_cmd) == VK_SUCCESS, "the engine ends its command buffer");
    CHECK_HRT(hrt_task_container_destroy(frame));
    /* Destroyed objects are recognised, not dereferenced: a second destroy, or any call on a
     * destroyed object, is HRT_ERROR_INVALID_HANDLE (and so is a container passed as a context). */
    EXPECT(hrt_task_container_destroy(frame) == HRT_ERROR_INVALID_HANDLE, "container destroyed twice");
    EXPECT(hrt_schedule_bvh_build(frame, &bvh) == HRT_ERROR_INVALID_HANDLE, "a destroyed container");
    EXPECT(hrt_task_container_len(frame) == 0, "a destroyed container has no tasks");
    EXPECT(hrt_release_device_resources_immediately((HrtContext *)frame) == HRT_ERROR_INVALID_HANDLE, "not a context");
    /* The lost ticket holds the plain destroy back; after a device loss the context is
     * destroyed without it, everything freed at once (the validation layer checks at
     * vkDestroyDevice that nothing of the SDK's is left). */
    EXPECT(hrt_context_destroy(ctx) == HRT_ERROR_TICKETS_IN_FLIGHT, "a ticket that never ran holds the context");
    CHECK_HRT(hrt_context_destroy_after_device_lost(ctx));
    EXPECT(hrt_context_destroy(ctx) == HRT_ERROR_INVALID_HANDLE, "context destroyed twice");
    EXPECT(hrt_context_destroy_after_device_lost(NULL) == HRT_OK, "NULL is ignored");
    HrtTaskContainer *late = NULL;
    EXPECT(hrt_task_container_create(ctx, &late) == HRT_ERROR_INVALID_HANDLE && !late, "a destroyed context");
    EXPECT(hrt_context_destroy(NULL) == HRT_OK, "NULL is ignored");
    free_image(depth);
    free_image(normals);
    free_image(out);
    free_buffer(vb_ground);
    free_buffer(vb_ceiling);
    free_buffer(ib16);
    free_buffer(ib);
    engine_destroy();
    EXPECT(validation_errors == 0, "%d validation errors", validation_errors);
    printf("c_api: all checks passed%s\n", validation ? " (with validation)" : "");
    return 0;
}
