// The header as a C++ program sees it: it compiles as C++17 with every warning an error, its
// structs and defaults are usable from C++, and the program runs against the shared library of
// the build tree (no install step). Prints what it checked.
#include <hybrid_rt.h>

#include <cstdio>
#include <cstring>

int main() {
    uint32_t major = 0, minor = 0, patch = 0;
    hrt_version(&major, &minor, &patch);
    const uint32_t library = (major << 22) | (minor << 12) | patch;
    if ((library >> 12) != (HRT_API_VERSION >> 12)) {
        std::printf("header %u, library %u.%u.%u\n", HRT_API_VERSION, major, minor, patch);
        return 1;
    }
    if (std::strcmp(hrt_status_string(HRT_ERROR_INVALID_INPUT), "HRT_ERROR_INVALID_INPUT") != 0 ||
        std::strcmp(hrt_status_string(-1), "HRT_STATUS_UNKNOWN") != 0) {
        std::printf("hrt_status_string: wrong names\n");
        return 1;
    }
    // A call that fails names its field; the C++ caller reads it like a C one.
    HrtTraceAmbientOcclusionTask task = hrt_trace_ambient_occlusion_task_default();
    task.rays_per_pixel = 0;
    HrtStatus status = hrt_schedule_ambient_occlusion(nullptr, &task);
    char message[256];
    hrt_last_error_message(message, sizeof message);
    std::printf("%s: %s\n", hrt_status_string(status), message);
    if (status != HRT_ERROR_NULL_POINTER) return 1;
    std::printf("c++: header checks passed\n");
    return 0;
}
