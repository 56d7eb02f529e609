// A headless Vulkan compute harness for the tests of generated shaders: compiles GLSL or
// HLSL compute shaders to SPIR-V with glslangValidator, checks them with spirv-val, and
// runs them over float buffers and cube-map textures on a Vulkan device (Mesa's lavapipe
// on the CI machines).
//
// What a shader must declare to run under VulkanCompute::run, all descriptors in set 0
// (B = buffers.size(), C = cubes.size()):
//   - entry point `main`, local size (64, 1, 1): run() dispatches ceil(invocations / 64)
//     work groups in x, so the shader must bound its index by a count it is given;
//   - buffer k of `buffers` as a storage buffer at binding k, k = 0..B-1;
//   - cube k of `cubes` at binding B + k, k = 0..C-1, as a float cube texture, in one of
//     two forms (run() reads which from the SPIR-V and binds descriptors to match):
//       combined (GLSL's samplerCube): a combined image sampler at B + k;
//       separate (HLSL's TextureCube<float4> + SamplerState): a sampled image at B + k
//       and ONE sampler, shared by all cubes, at binding B + C
//     (it is the SPIR-V that counts: GLSL's textureCube + sampler is the separate form);
//     every one of the C cubes must be in the module, each at its own binding, and no
//     other texture, sampler or storage image. glslang's HLSL front end removes
//     resources the shader never uses, so an HLSL shader must sample every cube it is
//     given (a GLSL declaration is kept even unused);
//   - if it takes push constants, one push-constant block at offset 0 that fits push_size.
// Anything else (uniform buffers, descriptor arrays, other sets, a 2D or arrayed image,
// the two texture forms mixed, a missing or misplaced sampler) is refused by run() with
// the reason.
//
// The cubes are sampled with linear filtering (mag and min; one mip level, so the
// shader passes LOD 0: a compute shader has no derivatives for an implicit LOD),
// clamp-to-edge addressing and normalised coordinates; Vulkan filters cube maps
// seamlessly across faces. A direction through a texel centre returns that texel: exactly
// when the centre's face coordinates are exact in float (a power-of-two size and |ma| a
// power of two), else to within the rounding of the coordinates.
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
// GLSL with one cube (B = 2 buffers, so the cube is at binding 2):
//   #version 450
//   layout(local_size_x = 64) in;
//   layout(push_constant) uniform Push { uint count; } pc;
//   layout(std430, set = 0, binding = 0) readonly buffer Dirs { float dirs[]; };
//   layout(std430, set = 0, binding = 1) writeonly buffer Out { vec4 o[]; };
//   layout(set = 0, binding = 2) uniform samplerCube bands0;
//   void main() {
//     uint i = gl_GlobalInvocationID.x;
//     if (i >= pc.count) return;
//     vec3 dir = vec3(dirs[3 * i], dirs[3 * i + 1], dirs[3 * i + 2]);
//     o[i] = textureLod(bands0, dir, 0.0);
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
// HLSL with one cube (B = 2, C = 1: the texture at binding 2, its sampler at 3):
//   struct Push { uint count; };
//   [[vk::push_constant]] ConstantBuffer<Push> pc;
//   StructuredBuffer<float> dirs : register(t0);
//   RWStructuredBuffer<float4> o : register(u1);
//   [[vk::binding(2, 0)]] TextureCube<float4> bands0;
//   [[vk::binding(3, 0)]] SamplerState bands_sampler;
//   [numthreads(64, 1, 1)]
//   void main(uint3 id : SV_DispatchThreadID) {
//     if (id.x >= pc.count) return;
//     float3 dir = float3(dirs[3 * id.x], dirs[3 * id.x + 1], dirs[3 * id.x + 2]);
//     o[id.x] = bands0.SampleLevel(bands_sampler, dir, 0);
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

// One cube map of RGBA float texels: faces in Vulkan layer order +X, -X, +Y, -Y, +Z, -Z, each
// size x size texels, row-major (row = t from 0, column = s from 0, as Vulkan addresses a
// face), 4 floats per texel: texels.size() == 6 * size * size * 4. Texel (column i, row j)
// of face f, channel c, is texels[((f * size + j) * size + i) * 4 + c]. Vulkan picks the
// face by the major axis ma of the direction and its coordinates (sc, tc) by
//   +X: sc = -z, tc = -y;  -X: sc = +z, tc = -y;  +Y: sc = +x, tc = +z;
//   -Y: sc = +x, tc = -z;  +Z: sc = +x, tc = -y;  -Z: sc = -x, tc = -y;
// s = (sc / |ma| + 1) / 2, t = (tc / |ma| + 1) / 2; texel i's centre is s = (i + 0.5) / size.
struct CubeTexture {
  int size = 0;
  std::vector<float> texels;
};

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
  // the module's interface and the arguments. The module may not use any texture.
  void run(const std::vector<uint32_t>& spirv, std::vector<std::vector<float>>& buffers, uint32_t invocations,
           const void* push_constants = nullptr, uint32_t push_size = 0);

  // As above, and binds cubes[k] at binding buffers.size() + k (with one sampler after
  // them if the module uses separate images and samplers; see the top of this file).
  // Each cube becomes a VK_FORMAT_R32G32B32A32_SFLOAT cube image of one mip level,
  // filtered linearly. Throws std::runtime_error for a cube of a bad size or texel count,
  // and when the device cannot filter that format linearly.
  void run(const std::vector<uint32_t>& spirv, std::vector<std::vector<float>>& buffers, uint32_t invocations,
           const void* push_constants, uint32_t push_size, const std::vector<CubeTexture>& cubes);

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
