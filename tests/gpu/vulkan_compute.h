// A headless Vulkan compute harness for the tests of generated shaders: compiles GLSL or
// HLSL compute shaders to SPIR-V with glslangValidator, checks them with spirv-val, and
// runs them over float buffers on a Vulkan device (Mesa's lavapipe on the CI machines).
//
// What a shader must declare to run under VulkanCompute::run:
//   - entry point `main`, local size (64, 1, 1): run() dispatches ceil(invocations / 64)
//     work groups in x, so the shader must bound its index by a count it is given;
//   - buffer k of `buffers` as a storage buffer at set 0, binding k (no other descriptors);
//   - if it takes push constants, one push-constant block at offset 0 that fits push_size.
//
// GLSL:
//   #version 450
//   layout(local_size_x = 64) in;
//   layout(push_constant) uniform Push { uint count; } pc;
//   layout(std430, set = 0, binding = 0) readonly buffer A { float a[]; };
//   layout(std430, set = 0, binding = 1) writeonly buffer Out { float o[]; };
//   void main() {
//     uint i = gl_GlobalInvocationID.x;
//     if (i < pc.count) o[i] = 2.0 * a[i];
//   }
//
// HLSL (glslang's front end, no --auto-map-bindings and no binding shifts): the register
// number is the binding and the space is the set, whatever the register class, so give
// every buffer its own number, register(uK) (or register(tK) for a read-only
// StructuredBuffer), or write [[vk::binding(K, 0)]]. A buffer without a register gets
// binding 0, colliding with buffer 0; run() rejects such collisions. Push constants must
// be a [[vk::push_constant]] cbuffer or ConstantBuffer<T>: a plain global (`uint count;`
// or `[[vk::push_constant]] PC pc;`) lands in the implicit $Global *uniform* buffer at
// binding 0, which run() rejects too.
//   struct Push { uint count; };
//   [[vk::push_constant]] ConstantBuffer<Push> pc;
//   StructuredBuffer<float> a : register(t0);
//   RWStructuredBuffer<float> o : register(u1);
//   [numthreads(64, 1, 1)]
//   void main(uint3 id : SV_DispatchThreadID) {
//     if (id.x < pc.count) o[id.x] = 2.0 * a[id.x];
//   }
//
// Floating point: Vulkan lets a device fuse a * b + c unless the result is marked
// `precise` (GLSL and HLSL alike; SPIR-V NoContraction), so shaders compared bit for bit
// against the CPU should say `precise` where contraction would change the result.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <vulkan/vulkan.h>

namespace shtool::gpu {

enum class ShaderLanguage { glsl, hlsl };

// SPIR-V for Vulkan 1.0 of a compute shader with entry point `main`. Throws
// std::runtime_error with the compiler's full output and the numbered source on failure;
// `log`, if given, receives the compiler's output either way (warnings on success).
std::vector<uint32_t> compile_compute(const std::string& source, ShaderLanguage lang, std::string* log = nullptr);

// Runs spirv-val --target-env vulkan1.0; throws std::runtime_error with its output if the
// module is rejected.
void validate_spirv(const std::vector<uint32_t>& spirv);

// One Vulkan instance, device and compute queue. run() may be called from several
// threads (it serialises on the queue).
class VulkanCompute {
 public:
  // nullptr, and the reason in *why_not, when there is no usable Vulkan instance or no
  // physical device with a compute queue. Prefers a CPU device (lavapipe) when there are
  // several, so results do not depend on which GPU a developer has.
  static std::unique_ptr<VulkanCompute> create(std::string* why_not);

  ~VulkanCompute();
  VulkanCompute(const VulkanCompute&) = delete;
  VulkanCompute& operator=(const VulkanCompute&) = delete;

  std::string device_name() const;

  // Binds buffers[k] as the storage buffer at set 0, binding k (at least 4 bytes), pushes
  // push_size bytes (a multiple of 4, at most 128) at offset 0, dispatches
  // ceil(invocations / 64) work groups, waits, and copies every buffer back into
  // `buffers` (inputs too, so a shader that writes where it should not is seen). Throws
  // std::runtime_error naming the Vulkan call and its VkResult, or the mismatch between
  // the module's interface and the arguments.
  void run(const std::vector<uint32_t>& spirv, std::vector<std::vector<float>>& buffers, uint32_t invocations,
           const void* push_constants = nullptr, uint32_t push_size = 0);

 private:
  VulkanCompute() = default;

  VkInstance instance_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t queue_family_ = 0;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_{};
  std::mutex queue_mutex_;
};

// SHTOOL_SKIP_GPU_TESTS=1: the developer has no Vulkan device and asks for the GPU tests
// to be skipped rather than failed.
bool gpu_tests_skipped_by_request();

// The process-wide device, created on first use (creating an instance per test would
// make the suite slow); nullptr, with the reason in *why_not, when there is none.
inline VulkanCompute* shared_device(std::string* why_not = nullptr) {
  struct Shared {
    std::unique_ptr<VulkanCompute> device;
    std::string why_not;
  };
  static Shared shared = [] {
    Shared s;
    s.device = VulkanCompute::create(&s.why_not);
    return s;
  }();
  if (why_not) *why_not = shared.why_not;
  return shared.device.get();
}

}  // namespace shtool::gpu

// At the top of a GPU test body (or SetUp): fails the test when there is no Vulkan device,
// so CI without lavapipe cannot pass silently; skips instead only when the developer set
// SHTOOL_SKIP_GPU_TESTS=1. Afterwards *shtool::gpu::shared_device() is usable.
#define SHTOOL_REQUIRE_VULKAN()                                                                                \
  do {                                                                                                         \
    std::string shtool_vulkan_why_not_;                                                                        \
    if (!::shtool::gpu::shared_device(&shtool_vulkan_why_not_)) {                                              \
      if (::shtool::gpu::gpu_tests_skipped_by_request()) {                                                     \
        GTEST_SKIP() << "no Vulkan device (" << shtool_vulkan_why_not_ << "); SHTOOL_SKIP_GPU_TESTS=1 is set"; \
      }                                                                                                        \
      FAIL() << "no Vulkan device: " << shtool_vulkan_why_not_                                                 \
             << "\ninstall mesa-vulkan-drivers (lavapipe), or set SHTOOL_SKIP_GPU_TESTS=1 to skip on a "       \
                "machine without Vulkan";                                                                      \
    }                                                                                                          \
  } while (0)
