/*
 * hybrid-rt from C in a page: ray-traced ambient occlusion on an engine's G-buffer.
 *
 * engine.c stands for the engine: its Vulkan device (made with the SDK's extensions and
 * features), buffers, images and command buffers. Everything below is what an integration
 * adds: a context on the engine's device, two meshes and their instances, an AO task on the
 * engine's depth and normals, recorded into the engine's command buffer, and the ticket
 * handed back once the engine's fence says the GPU is done. The ground is open; a small
 * ceiling 0.2 above it darkens the AO under it. Exit code 0 when the AO says so.
 */
#include "engine.h"
#include <math.h>
#include <string.h>

int main(void) {
    engine_create();

    /* A context on the engine's device: the same extensions and features it was made with. */
    HrtContextDesc desc = {0};
    desc.api_version = HRT_API_VERSION;
    desc.get_instance_proc_addr = (const void *)vkGetInstanceProcAddr;
    desc.instance = instance;
    desc.physical_device = physical_device;
    desc.device = device;
    desc.enabled_extensions = device_extensions;
    desc.enabled_extension_count = device_extension_count;
    desc.instance_api_version = VK_API_VERSION_1_3;
    desc.enabled_features = &device_features;
    desc.debug_utils = validation;
    desc.settings = hrt_init_settings_default();
    HrtContext *ctx = NULL;
    CHECK_HRT(hrt_context_create(&desc, &ctx));

    /* The meshes, as the engine holds them: a 20x20 ground at y = 0, a 1x1 ceiling at 0.2. */
    const float ground[] = {-10, 0, -10, 10, 0, -10, 10, 0, 10, -10, 0, 10};
    const float ceiling[] = {-0.5f, 0.2f, -0.5f, 0.5f, 0.2f, -0.5f, 0.5f, 0.2f, 0.5f, -0.5f, 0.2f, 0.5f};
    const uint32_t indices[] = {0, 2, 1, 0, 3, 2};
    Buffer vertices[2] = {make_buffer(sizeof ground, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, ground),
                          make_buffer(sizeof ceiling, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, ceiling)};
    Buffer index_buffer = make_buffer(sizeof indices, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, indices);

    /* Each mesh becomes a geometry (a BLAS), each placement an instance (a TLAS entry). */
    HrtTaskContainer *frame = NULL;
    CHECK_HRT(hrt_task_container_create(ctx, &frame));
    for (int i = 0; i < 2; i++) {
        HrtGeometryTask geometry = hrt_geometry_task_default();
        CHECK_HRT(hrt_create_geometry_handle(ctx, &geometry.handle));
        geometry.input.vertices.buffer = vertices[i].buffer;
        geometry.input.vertices.count = 4;
        geometry.input.indices.buffer = index_buffer.buffer;
        geometry.input.indices.count = 6;
        CHECK_HRT(hrt_schedule_geometry(frame, &geometry));
        HrtInstanceTask placed = hrt_instance_task_default(); /* identity transform */
        CHECK_HRT(hrt_create_instance_handle(ctx, &placed.handle));
        placed.input.geometry = geometry.handle;
        CHECK_HRT(hrt_schedule_instance(frame, &placed));
    }
    HrtBvhBuildTask bvh = hrt_bvh_build_task_default();
    CHECK_HRT(hrt_schedule_bvh_build(frame, &bvh));

    /* The engine's G-buffer: a camera 3 above the ground looking down (-Y); every pixel sees
     * the ground, so depth is one value and normals are +Y. */
    const float near = 0.05f, far = 100.0f, f = 1.0f / tanf(30.0f * 3.14159265f / 180.0f);
    const float ground_depth = (far / (near - far) * -3.0f + near * far / (near - far)) / 3.0f;
    Image depth = filled_image(VK_FORMAT_R32_SFLOAT, ground_depth, 0, 0, 0);
    Image normals = filled_image(VK_FORMAT_R32G32B32A32_SFLOAT, 0, 1, 0, 0);
    Image ao_image = make_image(VK_FORMAT_R32_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT);

    HrtTraceAmbientOcclusionTask ao = hrt_trace_ambient_occlusion_task_default();
    ao.common.depth.image = sdk_image(&depth, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    ao.common.normals.image = sdk_image(&normals, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    ao.common.normals.normal_type = HRT_NORMAL_RGB_VECTOR;
    ao.common.viewport.width = W;
    ao.common.viewport.height = H;
    const HrtCamera camera = {
        {1, 0, 0, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 0, -3, 1},                       /* world_to_view */
        {f, 0, 0, 0, 0, -f, 0, 0, 0, 0, far / (near - far), -1, 0, 0, near * far / (near - far), 0}, /* view_to_clip */
    };
    ao.common.camera = camera;
    ao.output = sdk_image(&ao_image, VK_IMAGE_LAYOUT_GENERAL);
    ao.ray_length = 1.0f;
    ao.rays_per_pixel = 16;
    CHECK_HRT(hrt_schedule_ambient_occlusion(frame, &ao));

    /* Recorded into the engine's command buffer, between the engine's own commands. */
    VkCommandBuffer cmd = begin();
    transition(cmd, ao_image.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
    HrtTicket ticket;
    CHECK_HRT(hrt_build_gpu_task(ctx, frame, cmd, &ticket));
    Buffer readback = record_readback(cmd, &ao_image, VK_IMAGE_LAYOUT_GENERAL, sizeof(float));
    submit_and_wait(cmd);
    /* The GPU is done with the frame: the SDK recycles what it used. */
    CHECK_HRT(hrt_mark_gpu_task_completed(ctx, ticket, NULL, 0, NULL));

    float result[W * H];
    read_and_free(readback, sizeof result, result);
    const float under = result[(H / 2) * W + W / 2], open = result[0];
    printf("AO under the ceiling %.3f, in the open %.3f\n", under, open);

    CHECK_HRT(hrt_task_container_destroy(frame));
    CHECK_HRT(hrt_context_destroy(ctx)); /* its geometries and instances with it */
    free_image(depth);
    free_image(normals);
    free_image(ao_image);
    free_buffer(vertices[0]);
    free_buffer(vertices[1]);
    free_buffer(index_buffer);
    engine_destroy();
    int ok = under < 0.6f && open > 0.999f && validation_errors == 0;
    printf("c ao: %s\n", ok ? "passed" : "FAILED");
    return ok ? 0 : 1;
}
