/*
 * The engine of the C samples: what a Vulkan engine already has before it adds hybrid-rt (an
 * instance, a device with one queue, buffers, images, command buffers, a fence), plus the
 * SDK's part of device creation: its extensions and features. Kept apart so that the samples
 * read as the SDK calls an integration makes.
 */
#include "engine.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

VkInstance instance;
VkPhysicalDevice physical_device;
VkDevice device;
VkQueue queue;
VkCommandPool pool;
const char *device_extensions[16];
uint32_t device_extension_count;
VkPhysicalDeviceFeatures2 device_features = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
int validation;
int validation_errors;

static VkPhysicalDeviceMemoryProperties memory_properties;
static VkPhysicalDeviceVulkan13Features own13 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
static HrtDeviceFeatures *sdk_features;
static VkDebugUtilsMessengerEXT messenger;

static VKAPI_ATTR VkBool32 VKAPI_CALL on_validation(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                    VkDebugUtilsMessageTypeFlagsEXT type,
                                                    const VkDebugUtilsMessengerCallbackDataEXT *data, void *user) {
    (void)type;
    (void)user;
    /* Best-practices notes about this program's own one-allocation-per-resource style; the
     * SDK allocates through large blocks and never triggers them. */
    static const char *const ignored[] = {
        "UNASSIGNED-BestPractices-vkAllocateMemory-small-allocation",
        "UNASSIGNED-BestPractices-vkBindMemory-small-dedicated-allocation",
        "UNASSIGNED-BestPractices-vkCreateCommandPool-command-buffer-reset",
    };
    int error = (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) != 0;
    if (!error && data->pMessageIdName) {
        for (size_t i = 0; i < sizeof ignored / sizeof ignored[0]; i++) {
            if (strcmp(data->pMessageIdName, ignored[i]) == 0) return VK_FALSE;
        }
    }
    if (error || (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT)) {
        validation_errors++;
        fprintf(stderr, "[validation %s] %s\n", error ? "error" : "warning", data->pMessage);
    }
    return VK_FALSE;
}

void log_sdk_message(HrtLogSeverity severity, const char *message, void *user) {
    (void)user;
    fprintf(stderr, "[hybrid-rt %d] %s\n", (int)severity, message);
}

static uint32_t memory_type(uint32_t bits, VkMemoryPropertyFlags flags) {
    for (uint32_t i = 0; i < memory_properties.memoryTypeCount; i++)
        if ((bits & (1u << i)) && (memory_properties.memoryTypes[i].propertyFlags & flags) == flags) return i;
    fprintf(stderr, "no memory type\n");
    exit(1);
}


Buffer make_buffer(VkDeviceSize size, VkBufferUsageFlags usage, const void *data) {
    Buffer b;
    VkBufferCreateInfo info = {VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.size = size;
    info.usage = usage;
    CHECK_VK(vkCreateBuffer(device, &info, NULL, &b.buffer));
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(device, b.buffer, &req);
    VkMemoryAllocateInfo alloc = {VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    alloc.allocationSize = req.size;
    alloc.memoryTypeIndex = memory_type(req.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    CHECK_VK(vkAllocateMemory(device, &alloc, NULL, &b.memory));
    CHECK_VK(vkBindBufferMemory(device, b.buffer, b.memory, 0));
    if (data) {
        void *p;
        CHECK_VK(vkMapMemory(device, b.memory, 0, size, 0, &p));
        memcpy(p, data, (size_t)size);
        vkUnmapMemory(device, b.memory);
    }
    return b;
}

void free_buffer(Buffer b) {
    vkDestroyBuffer(device, b.buffer, NULL);
    vkFreeMemory(device, b.memory, NULL);
}


Image make_image(VkFormat format, VkImageUsageFlags usage) {
    Image img;
    img.format = format;
    VkImageCreateInfo info = {VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = format;
    info.extent.width = W;
    info.extent.height = H;
    info.extent.depth = 1;
    info.mipLevels = 1;
    info.arrayLayers = 1;
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    info.usage = usage | VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    img.usage = info.usage;
    CHECK_VK(vkCreateImage(device, &info, NULL, &img.image));
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(device, img.image, &req);
    VkMemoryAllocateInfo alloc = {VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    alloc.allocationSize = req.size;
    alloc.memoryTypeIndex = memory_type(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    CHECK_VK(vkAllocateMemory(device, &alloc, NULL, &img.memory));
    CHECK_VK(vkBindImageMemory(device, img.image, img.memory, 0));
    VkImageViewCreateInfo view = {VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    view.image = img.image;
    view.viewType = VK_IMAGE_VIEW_TYPE_2D;
    view.format = format;
    view.subresourceRange.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
    view.subresourceRange.levelCount = 1;
    view.subresourceRange.layerCount = 1;
    CHECK_VK(vkCreateImageView(device, &view, NULL, &img.view));
    return img;
}

void free_image(Image i) {
    vkDestroyImageView(device, i.view, NULL);
    vkDestroyImage(device, i.image, NULL);
    vkFreeMemory(device, i.memory, NULL);
}

HrtImageInput sdk_image(const Image *i, VkImageLayout layout) {
    HrtImageInput in;
    in.image = i->image;
    in.view = i->view;
    in.format = i->format;
    in.width = W;
    in.height = H;
    in.layout = layout;
    in.usage = i->usage;
    return in;
}

/* The stages this program and the SDK work in (the SDK's reads and writes are ray-tracing and
 * compute shaders, acceleration-structure builds and copies). */
static const VkPipelineStageFlags2 WORK_STAGES = VK_PIPELINE_STAGE_2_COPY_BIT | VK_PIPELINE_STAGE_2_CLEAR_BIT |
                                                 VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT |
                                                 VK_PIPELINE_STAGE_2_RAY_TRACING_SHADER_BIT_KHR |
                                                 VK_PIPELINE_STAGE_2_ACCELERATION_STRUCTURE_BUILD_BIT_KHR;

/* What an image in `layout` is accessed with (leaving it: the writes to wait for). */
static VkAccessFlags2 layout_access(VkImageLayout layout, int leaving) {
    switch (layout) {
    case VK_IMAGE_LAYOUT_UNDEFINED: return VK_ACCESS_2_NONE;
    case VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL: return VK_ACCESS_2_TRANSFER_WRITE_BIT;
    case VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL: return VK_ACCESS_2_TRANSFER_READ_BIT;
    case VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL: return VK_ACCESS_2_SHADER_READ_BIT;
    default: return leaving ? VK_ACCESS_2_MEMORY_WRITE_BIT : VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT;
    }
}

void transition(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to) {
    VkImageMemoryBarrier2 b = {VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
    b.srcStageMask = WORK_STAGES;
    b.srcAccessMask = layout_access(from, 1);
    b.dstStageMask = WORK_STAGES;
    b.dstAccessMask = layout_access(to, 0);
    b.oldLayout = from;
    b.newLayout = to;
    b.image = image;
    b.subresourceRange.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
    b.subresourceRange.levelCount = 1;
    b.subresourceRange.layerCount = 1;
    VkDependencyInfo dep = {VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    dep.imageMemoryBarrierCount = 1;
    dep.pImageMemoryBarriers = &b;
    vkCmdPipelineBarrier2(cmd, &dep);
}

VkCommandBuffer begin(void) {
    VkCommandBufferAllocateInfo info = {VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    info.commandPool = pool;
    info.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    info.commandBufferCount = 1;
    VkCommandBuffer cmd;
    CHECK_VK(vkAllocateCommandBuffers(device, &info, &cmd));
    VkCommandBufferBeginInfo bi = {VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    CHECK_VK(vkBeginCommandBuffer(cmd, &bi));
    return cmd;
}

void submit_and_wait(VkCommandBuffer cmd) {
    CHECK_VK(vkEndCommandBuffer(cmd));
    VkFenceCreateInfo fi = {VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence;
    CHECK_VK(vkCreateFence(device, &fi, NULL, &fence));
    VkSubmitInfo si = {VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cmd;
    CHECK_VK(vkQueueSubmit(queue, 1, &si, fence));
    CHECK_VK(vkWaitForFences(device, 1, &fence, VK_TRUE, UINT64_MAX));
    vkDestroyFence(device, fence, NULL);
    vkFreeCommandBuffers(device, pool, 1, &cmd);
}

/* A sampled image filled with one colour, left in SHADER_READ_ONLY_OPTIMAL. */
Image filled_image(VkFormat format, float r, float g, float b, float a) {
    Image img = make_image(format, VK_IMAGE_USAGE_SAMPLED_BIT);
    VkCommandBuffer cmd = begin();
    VkClearColorValue value = {{r, g, b, a}};
    VkImageSubresourceRange all = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    transition(cmd, img.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    vkCmdClearColorImage(cmd, img.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &value, 1, &all);
    transition(cmd, img.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    submit_and_wait(cmd);
    return img;
}

Buffer record_readback(VkCommandBuffer cmd, const Image *i, VkImageLayout layout, uint32_t texel_bytes) {
    Buffer readback = make_buffer((VkDeviceSize)W * H * texel_bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, NULL);
    transition(cmd, i->image, layout, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    VkBufferImageCopy region = {0};
    region.imageSubresource.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
    region.imageSubresource.layerCount = 1;
    region.imageExtent.width = W;
    region.imageExtent.height = H;
    region.imageExtent.depth = 1;
    vkCmdCopyImageToBuffer(cmd, i->image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback.buffer, 1, &region);
    transition(cmd, i->image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, layout);
    return readback;
}

void read_and_free(Buffer b, size_t size, void *out) {
    void *p;
    CHECK_VK(vkMapMemory(device, b.memory, 0, size, 0, &p));
    memcpy(out, p, size);
    vkUnmapMemory(device, b.memory);
    free_buffer(b);
}

void engine_create(void) {
    uint32_t layer_count = 0;
    vkEnumerateInstanceLayerProperties(&layer_count, NULL);
    VkLayerProperties *layers = calloc(layer_count ? layer_count : 1, sizeof *layers);
    vkEnumerateInstanceLayerProperties(&layer_count, layers);
    const char *env = getenv("HRT_VALIDATION");
    for (uint32_t i = 0; i < layer_count; i++)
        if (!strcmp(layers[i].layerName, "VK_LAYER_KHRONOS_validation") && !(env && !strcmp(env, "0"))) validation = 1;
    free(layers);
    const char *layer_names[] = {"VK_LAYER_KHRONOS_validation"};
    const char *instance_exts[] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME};

    VkApplicationInfo app = {VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "hybrid-rt C sample";
    app.apiVersion = VK_API_VERSION_1_3;
    VkInstanceCreateInfo ici = {VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ici.pApplicationInfo = &app;
    ici.enabledLayerCount = validation ? 1 : 0;
    ici.ppEnabledLayerNames = layer_names;
    ici.enabledExtensionCount = validation ? 1 : 0;
    ici.ppEnabledExtensionNames = instance_exts;
    CHECK_VK(vkCreateInstance(&ici, NULL, &instance));
    if (validation) {
        PFN_vkCreateDebugUtilsMessengerEXT create =
            (PFN_vkCreateDebugUtilsMessengerEXT)vkGetInstanceProcAddr(instance, "vkCreateDebugUtilsMessengerEXT");
        VkDebugUtilsMessengerCreateInfoEXT mi = {VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
        mi.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT;
        mi.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT;
        mi.pfnUserCallback = on_validation;
        CHECK_VK(create(instance, &mi, NULL, &messenger));
    }

    uint32_t device_count = 0;
    CHECK_VK(vkEnumeratePhysicalDevices(instance, &device_count, NULL));
    VkPhysicalDevice devices[16];
    if (device_count > 16) device_count = 16;
    CHECK_VK(vkEnumeratePhysicalDevices(instance, &device_count, devices));
    bool ray_query = false;
    char missing[512];
    for (uint32_t i = 0; i < device_count && !physical_device; i++) {
        bool supported = false, rq = false;
        CHECK_HRT(hrt_query_device_support((const void *)vkGetInstanceProcAddr, instance, devices[i], &supported, &rq, missing, sizeof missing));
        if (supported) {
            physical_device = devices[i];
            ray_query = rq;
        } else {
            printf("device %u lacks: %s\n", i, missing);
        }
    }
    EXPECT(physical_device != VK_NULL_HANDLE, "a device with ray tracing (run scripts/setup.sh)");
    vkGetPhysicalDeviceMemoryProperties(physical_device, &memory_properties);

    uint32_t family_count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(physical_device, &family_count, NULL);
    VkQueueFamilyProperties families[16];
    if (family_count > 16) family_count = 16;
    vkGetPhysicalDeviceQueueFamilyProperties(physical_device, &family_count, families);
    uint32_t family = 0;
    while (family < family_count && !(families[family].queueFlags & VK_QUEUE_COMPUTE_BIT)) family++;

    /* Extensions and features the SDK asks for. */
    const char *const *required;
    const char *const *optional;
    uint32_t n_required, n_optional;
    hrt_required_device_extensions(&required, &n_required);
    hrt_optional_device_extensions(&optional, &n_optional);
    for (uint32_t i = 0; i < n_required; i++) device_extensions[device_extension_count++] = required[i];
    if (ray_query)
        for (uint32_t i = 0; i < n_optional; i++) device_extensions[device_extension_count++] = optional[i];

    /* The engine's own feature chain (here: Vulkan 1.3 features it wants for itself). The SDK's
     * features are merged into it: switched on in the structs it has, the others appended. */
    own13.dynamicRendering = VK_TRUE;
    device_features.pNext = &own13;
    sdk_features = hrt_device_features_create(ray_query);
    CHECK_HRT(hrt_device_features_merge(sdk_features, &device_features));
    EXPECT(own13.synchronization2, "the SDK's 1.3 feature is set in the engine's own struct");

    float priority = 1.0f;
    VkDeviceQueueCreateInfo qci = {VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qci.queueFamilyIndex = family;
    qci.queueCount = 1;
    qci.pQueuePriorities = &priority;
    VkDeviceCreateInfo dci = {VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    dci.pNext = &device_features;
    dci.queueCreateInfoCount = 1;
    dci.pQueueCreateInfos = &qci;
    dci.enabledExtensionCount = device_extension_count;
    dci.ppEnabledExtensionNames = device_extensions;
    CHECK_VK(vkCreateDevice(physical_device, &dci, NULL, &device));
    vkGetDeviceQueue(device, family, 0, &queue);
    VkCommandPoolCreateInfo pci = {VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pci.queueFamilyIndex = family;
    CHECK_VK(vkCreateCommandPool(device, &pci, NULL, &pool));
}

void engine_destroy(void) {
    hrt_device_features_destroy(sdk_features);
    vkDestroyCommandPool(device, pool, NULL);
    vkDestroyDevice(device, NULL);
    if (messenger) {
        PFN_vkDestroyDebugUtilsMessengerEXT destroy =
            (PFN_vkDestroyDebugUtilsMessengerEXT)vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT");
        destroy(instance, messenger, NULL);
    }
    vkDestroyInstance(instance, NULL);
}
