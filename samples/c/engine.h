/*
 * The engine of the C samples (engine.c): a Vulkan instance and device made with what the
 * SDK needs, and the buffers, images and command buffers every engine has helpers for.
 */
#ifndef HRT_SAMPLE_ENGINE_H
#define HRT_SAMPLE_ENGINE_H
#include "hybrid_rt.h"
#include <stdio.h>
#include <stdlib.h>

/* The size of the samples' G-buffer. */
#define W 32
#define H 32

#define CHECK_VK(x)                                                                  \
    do {                                                                             \
        VkResult r_ = (x);                                                           \
        if (r_ != VK_SUCCESS) {                                                      \
            fprintf(stderr, "%s:%d: %s -> VkResult %d\n", __FILE__, __LINE__, #x, r_); \
            exit(1);                                                                 \
        }                                                                            \
    } while (0)

#define CHECK_HRT(x)                                                                           \
    do {                                                                                       \
        HrtStatus s_ = (x);                                                                    \
        if (s_ != HRT_OK) {                                                                    \
            char m_[512];                                                                      \
            hrt_last_error_message(m_, sizeof m_);                                             \
            fprintf(stderr, "%s:%d: %s -> status %d: %s\n", __FILE__, __LINE__, #x, s_, m_); \
            exit(1);                                                                           \
        }                                                                                      \
    } while (0)

#define EXPECT(cond, ...)                                                 \
    do {                                                                  \
        if (!(cond)) {                                                    \
            fprintf(stderr, "%s:%d: check failed: %s: ", __FILE__, __LINE__, #cond); \
            fprintf(stderr, __VA_ARGS__);                                 \
            fprintf(stderr, "\n");                                        \
            exit(1);                                                      \
        }                                                                 \
    } while (0)

typedef struct {
    VkBuffer buffer;
    VkDeviceMemory memory;
} Buffer;

typedef struct {
    VkImage image;
    VkDeviceMemory memory;
    VkImageView view;
    VkFormat format;
    VkImageUsageFlags usage; /* as created: the SDK checks each image has the usage it needs */
} Image;

/* Made by engine_create. */
extern VkInstance instance;
extern VkPhysicalDevice physical_device;
extern VkDevice device;
extern VkQueue queue;
extern VkCommandPool pool;
/* What the device was created with: the SDK's context is told the same. */
extern const char *device_extensions[16];
extern uint32_t device_extension_count;
extern VkPhysicalDeviceFeatures2 device_features;
/* The Khronos validation layer is on (installed, and HRT_VALIDATION is not 0); its errors and
 * warnings so far. */
extern int validation;
extern int validation_errors;

/* The instance (with validation when installed), the first device the SDK supports, its
 * device with the SDK's extensions and features merged into the engine's own. */
void engine_create(void);
/* Destroys what engine_create made; the SDK's objects must be gone first. */
void engine_destroy(void);
/* The SDK's log callback of the samples: prints to stderr. */
void log_sdk_message(HrtLogSeverity severity, const char *message, void *user);

/* Host-visible buffer, filled with `data` unless it is NULL. */
Buffer make_buffer(VkDeviceSize size, VkBufferUsageFlags usage, const void *data);
void free_buffer(Buffer b);
/* W x H device-local image with a view. */
Image make_image(VkFormat format, VkImageUsageFlags usage);
void free_image(Image i);
/* A sampled image filled with one colour, left in SHADER_READ_ONLY_OPTIMAL. */
Image filled_image(VkFormat format, float r, float g, float b, float a);
/* How the SDK is told of an image in `layout`. */
HrtImageInput sdk_image(const Image *i, VkImageLayout layout);
/* A layout transition between the samples' and the SDK's work (full stage masks). */
void transition(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to);
/* A one-time command buffer, begun. */
VkCommandBuffer begin(void);
/* Ends, submits and waits for `cmd`, then frees it. */
void submit_and_wait(VkCommandBuffer cmd);
/* Records a copy of `i` (in `layout`, where it is left) into a new host-visible buffer. */
Buffer record_readback(VkCommandBuffer cmd, const Image *i, VkImageLayout layout, uint32_t texel_bytes);
/* Copies `size` bytes of a submitted readback out, then frees it. */
void read_and_free(Buffer b, size_t size, void *out);
#endif
