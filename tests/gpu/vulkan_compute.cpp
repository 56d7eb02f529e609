// The Vulkan compute harness of the GPU tests: shader compilation through the glslang and
// SPIRV-Tools executables, a minimal reflection of the module against run()'s arguments,
// and one dispatch per run() over host-visible storage buffers and cube textures uploaded
// through a staging buffer.
#include "vulkan_compute.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <dlfcn.h>
#include <fcntl.h>
#include <link.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

#ifndef SHTOOL_GLSLANG_VALIDATOR
#error "SHTOOL_GLSLANG_VALIDATOR (the glslangValidator path) must be defined by the build"
#endif
#ifndef SHTOOL_SPIRV_VAL
#error "SHTOOL_SPIRV_VAL (the spirv-val path) must be defined by the build"
#endif

namespace shtool::gpu {
namespace {

namespace fs = std::filesystem;

constexpr uint32_t kLocalSize = 64;
constexpr uint32_t kMaxPushSize = 128;  // the minimum every Vulkan device guarantees

// ---------------------------------------------------------------------------------------
// Tools

// Files of one tool invocation, removed however the invocation ends. Names carry the pid
// and a counter so parallel test programs, and threads of one, never share a file.
class ScratchFiles {
 public:
  ScratchFiles() {
    static std::atomic<unsigned> counter{0};
    stem_ = fs::temp_directory_path() /
            ("shtool_gpu_" + std::to_string(::getpid()) + "_" + std::to_string(counter.fetch_add(1)));
  }
  ~ScratchFiles() {
    for (const fs::path& p : paths_) {
      std::error_code ec;
      fs::remove(p, ec);
    }
  }
  ScratchFiles(const ScratchFiles&) = delete;
  ScratchFiles& operator=(const ScratchFiles&) = delete;

  fs::path make(const std::string& suffix) {
    paths_.push_back(stem_.string() + suffix);
    return paths_.back();
  }

 private:
  fs::path stem_;
  std::vector<fs::path> paths_;
};

std::string read_text(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

void write_bytes(const fs::path& p, const void* data, size_t size) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  f.close();
  if (!f) throw std::runtime_error("cannot write " + p.string());
}

// Runs argv without a shell (no quoting of paths), stdout and stderr interleaved into
// `log` as a terminal would show them. Returns the exit code, 128 + signal if killed.
int run_tool(const std::vector<std::string>& argv, const fs::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string log_name = log.string();
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log_name.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw std::runtime_error("cannot run " + argv[0] + ": " + std::strerror(rc));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw std::runtime_error("waitpid for " + argv[0] + ": " + std::strerror(errno));
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

std::string numbered(const std::string& source) {
  std::ostringstream out;
  std::istringstream in(source);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    std::string num = std::to_string(n);
    out << std::string(num.size() < 4 ? 4 - num.size() : 0, ' ') << num << " | " << line << '\n';
  }
  return out.str();
}

std::string command_line(const std::vector<std::string>& argv) {
  std::string s;
  for (const std::string& a : argv) s += (s.empty() ? "" : " ") + a;
  return s;
}

// ---------------------------------------------------------------------------------------
// Vulkan errors

const char* result_name(VkResult r) {
  switch (r) {
#define SHTOOL_VK_RESULT(x) \
  case x:                   \
    return #x;
    SHTOOL_VK_RESULT(VK_SUCCESS)
    SHTOOL_VK_RESULT(VK_NOT_READY)
    SHTOOL_VK_RESULT(VK_TIMEOUT)
    SHTOOL_VK_RESULT(VK_EVENT_SET)
    SHTOOL_VK_RESULT(VK_EVENT_RESET)
    SHTOOL_VK_RESULT(VK_INCOMPLETE)
    SHTOOL_VK_RESULT(VK_ERROR_OUT_OF_HOST_MEMORY)
    SHTOOL_VK_RESULT(VK_ERROR_OUT_OF_DEVICE_MEMORY)
    SHTOOL_VK_RESULT(VK_ERROR_INITIALIZATION_FAILED)
    SHTOOL_VK_RESULT(VK_ERROR_DEVICE_LOST)
    SHTOOL_VK_RESULT(VK_ERROR_MEMORY_MAP_FAILED)
    SHTOOL_VK_RESULT(VK_ERROR_LAYER_NOT_PRESENT)
    SHTOOL_VK_RESULT(VK_ERROR_EXTENSION_NOT_PRESENT)
    SHTOOL_VK_RESULT(VK_ERROR_FEATURE_NOT_PRESENT)
    SHTOOL_VK_RESULT(VK_ERROR_INCOMPATIBLE_DRIVER)
    SHTOOL_VK_RESULT(VK_ERROR_TOO_MANY_OBJECTS)
    SHTOOL_VK_RESULT(VK_ERROR_FORMAT_NOT_SUPPORTED)
    SHTOOL_VK_RESULT(VK_ERROR_FRAGMENTED_POOL)
    SHTOOL_VK_RESULT(VK_ERROR_UNKNOWN)
    SHTOOL_VK_RESULT(VK_ERROR_OUT_OF_POOL_MEMORY)
    SHTOOL_VK_RESULT(VK_ERROR_INVALID_EXTERNAL_HANDLE)
    SHTOOL_VK_RESULT(VK_ERROR_FRAGMENTATION)
    SHTOOL_VK_RESULT(VK_ERROR_INVALID_OPAQUE_CAPTURE_ADDRESS)
    SHTOOL_VK_RESULT(VK_ERROR_INVALID_SHADER_NV)
#undef SHTOOL_VK_RESULT
    default:
      return nullptr;
  }
}

std::string describe(VkResult r) {
  const char* name = result_name(r);
  return name ? name : "VkResult " + std::to_string(static_cast<int>(r));
}

void check(VkResult r, const char* call) {
  if (r != VK_SUCCESS) throw std::runtime_error(std::string(call) + " failed: " + describe(r));
}

// ---------------------------------------------------------------------------------------
// Reflection: without validation layers a module whose interface does not match the
// pipeline layout is undefined behaviour (typically garbage or a crash), so run() checks
// the few things it relies on and says what is wrong instead.

namespace spv {
constexpr uint32_t kMagic = 0x07230203;
constexpr uint32_t OpEntryPoint = 15, OpExecutionMode = 16, OpTypeFloat = 22, OpTypeImage = 25, OpTypeSampler = 26,
                   OpTypeSampledImage = 27, OpTypeArray = 28, OpTypeRuntimeArray = 29, OpTypePointer = 32,
                   OpConstant = 43, OpConstantComposite = 44, OpSpecConstant = 50, OpSpecConstantComposite = 51,
                   OpVariable = 59, OpDecorate = 71, OpMemberDecorate = 72;
constexpr uint32_t ModelGLCompute = 5, ModeLocalSize = 17, ModeLocalSizeId = 38;
constexpr uint32_t DecBlock = 2, DecBufferBlock = 3, DecBuiltIn = 11, DecBinding = 33, DecDescriptorSet = 34,
                   DecOffset = 35, BuiltInWorkgroupSize = 25;
constexpr uint32_t ClassUniformConstant = 0, ClassUniform = 2, ClassPushConstant = 9, ClassStorageBuffer = 12;
constexpr uint32_t DimCube = 3;
}  // namespace spv

// How the module takes its cube textures, and so which descriptors run() binds.
enum class TextureForm {
  none,      // no textures (run() was given no cubes)
  combined,  // combined image samplers at B..B+C-1 (GLSL's samplerCube)
  separate,  // sampled images at B..B+C-1 and one sampler at B+C (HLSL's TextureCube + SamplerState)
};

std::string dim_name(uint32_t dim) {
  static const char* const names[] = {"1D", "2D", "3D", "cube", "rect", "buffer", "subpass-data"};
  return dim < std::size(names) ? names[dim] : "Dim " + std::to_string(dim);
}

std::string counted(size_t n, const std::string& noun) { return std::to_string(n) + " " + noun + (n == 1 ? "" : "s"); }

std::string binding_range(size_t first, size_t count) {
  if (count == 1) return "binding " + std::to_string(first);
  return "bindings " + std::to_string(first) + ".." + std::to_string(first + count - 1);
}

TextureForm check_interface(const std::vector<uint32_t>& code, size_t buffer_count, size_t cube_count,
                            uint32_t push_size) {
  auto fail = [](const std::string& what) { throw std::runtime_error("VulkanCompute::run: " + what); };
  if (code.size() < 5 || code[0] != spv::kMagic) fail("not a SPIR-V module (bad size or magic number)");

  struct ImageType {
    uint32_t sampled_type, dim, arrayed, ms, sampled;
  };
  bool has_main = false;
  uint32_t local[3] = {0, 0, 0};
  std::vector<uint32_t> local_size_ids;  // LocalSizeId operands
  uint32_t workgroup_size_id = 0;        // the WorkgroupSize built-in, which overrides both modes
  std::map<uint32_t, uint32_t> scalars;  // 32-bit (spec) constants: id -> value (default value if spec)
  std::map<uint32_t, std::vector<uint32_t>> composites;
  std::map<uint32_t, std::pair<uint32_t, uint32_t>> pointers;  // pointer type -> (class, pointee)
  std::vector<std::pair<uint32_t, uint32_t>> variables;        // (result id, pointer type)
  std::map<uint32_t, uint32_t> binding, set;
  std::set<uint32_t> blocks, buffer_blocks;
  std::map<uint32_t, uint32_t> max_member_offset;
  std::map<uint32_t, uint32_t> float_width;     // OpTypeFloat id -> width
  std::map<uint32_t, ImageType> images;         // OpTypeImage
  std::set<uint32_t> samplers;                  // OpTypeSampler
  std::map<uint32_t, uint32_t> sampled_images;  // OpTypeSampledImage -> its image type
  std::set<uint32_t> arrays;                    // OpTypeArray, OpTypeRuntimeArray
  for (size_t i = 5; i < code.size();) {
    const uint32_t count = code[i] >> 16, op = code[i] & 0xffff;
    if (count == 0 || i + count > code.size()) fail("malformed SPIR-V instruction stream");
    const uint32_t* w = &code[i];
    if (op == spv::OpEntryPoint && count >= 4 && w[1] == spv::ModelGLCompute) {
      has_main = has_main || std::strncmp(reinterpret_cast<const char*>(&w[3]), "main", (count - 3) * 4) == 0;
    } else if (op == spv::OpExecutionMode && count >= 6 && w[2] == spv::ModeLocalSize) {
      std::copy(w + 3, w + 6, local);
    } else if (op == spv::OpExecutionMode && count >= 6 && w[2] == spv::ModeLocalSizeId) {
      local_size_ids.assign(w + 3, w + 6);
    } else if ((op == spv::OpConstant || op == spv::OpSpecConstant) && count == 4) {
      scalars[w[2]] = w[3];
    } else if ((op == spv::OpConstantComposite || op == spv::OpSpecConstantComposite) && count >= 3) {
      composites[w[2]].assign(w + 3, w + count);
    } else if (op == spv::OpTypeFloat && count >= 3) {
      float_width[w[1]] = w[2];
    } else if (op == spv::OpTypeImage && count >= 9) {
      images[w[1]] = {w[2], w[3], w[5], w[6], w[7]};
    } else if (op == spv::OpTypeSampler && count >= 2) {
      samplers.insert(w[1]);
    } else if (op == spv::OpTypeSampledImage && count >= 3) {
      sampled_images[w[1]] = w[2];
    } else if ((op == spv::OpTypeArray || op == spv::OpTypeRuntimeArray) && count >= 3) {
      arrays.insert(w[1]);
    } else if (op == spv::OpTypePointer && count == 4) {
      pointers[w[1]] = {w[2], w[3]};
    } else if (op == spv::OpVariable && count >= 4) {
      variables.emplace_back(w[2], w[1]);
    } else if (op == spv::OpDecorate && count >= 3) {
      if (w[2] == spv::DecBinding && count >= 4) binding[w[1]] = w[3];
      if (w[2] == spv::DecDescriptorSet && count >= 4) set[w[1]] = w[3];
      if (w[2] == spv::DecBlock) blocks.insert(w[1]);
      if (w[2] == spv::DecBufferBlock) buffer_blocks.insert(w[1]);
      if (w[2] == spv::DecBuiltIn && count >= 4 && w[3] == spv::BuiltInWorkgroupSize) workgroup_size_id = w[1];
    } else if (op == spv::OpMemberDecorate && count >= 5 && w[3] == spv::DecOffset) {
      max_member_offset[w[1]] = std::max(max_member_offset[w[1]], w[4]);
    }
    i += count;
  }

  if (!has_main) fail("the module has no GLCompute entry point named \"main\"");
  // Specialisation constants keep their default values: run() specialises nothing.
  auto resolve = [&](const std::vector<uint32_t>& ids) {
    for (size_t k = 0; k < 3 && k < ids.size(); ++k) {
      const auto c = scalars.find(ids[k]);
      local[k] = c == scalars.end() ? 0 : c->second;
    }
  };
  if (!local_size_ids.empty()) resolve(local_size_ids);
  if (const auto c = composites.find(workgroup_size_id); workgroup_size_id != 0 && c != composites.end()) {
    resolve(c->second);
  }
  if (local[0] != kLocalSize || local[1] != 1 || local[2] != 1) {
    fail("the shader's local size is (" + std::to_string(local[0]) + ", " + std::to_string(local[1]) + ", " +
         std::to_string(local[2]) + "); run() dispatches work groups of (64, 1, 1)");
  }

  const size_t first_cube = buffer_count, sampler_binding = buffer_count + cube_count;
  const std::string cubes_given =
      cube_count == 0 ? std::string("no cube textures")
                      : counted(cube_count, "cube texture") + " (" + binding_range(first_cube, cube_count) + ")";
  std::map<uint32_t, uint32_t> used;                        // buffer binding -> variable
  std::map<uint32_t, uint32_t> combined, separate;          // texture binding -> variable, by form
  std::vector<std::pair<uint32_t, uint32_t>> sampler_vars;  // (variable, binding)
  for (const auto& [id, type] : variables) {
    const auto ptr = pointers.find(type);
    if (ptr == pointers.end()) continue;
    const auto [storage, pointee] = ptr->second;
    const std::string where = "variable %" + std::to_string(id);
    if (storage == spv::ClassPushConstant) {
      if (push_size == 0) fail("the shader declares push constants but run() was given none");
      const auto off = max_member_offset.find(pointee);
      if (off != max_member_offset.end() && off->second + 4 > push_size) {
        fail("the push-constant block has a member at offset " + std::to_string(off->second) + " but run() pushes " +
             std::to_string(push_size) + " bytes");
      }
      continue;
    }
    if (storage != spv::ClassUniform && storage != spv::ClassStorageBuffer && storage != spv::ClassUniformConstant) {
      continue;
    }
    const auto b = binding.find(id);
    const std::string at = b == binding.end() ? "" : " (binding " + std::to_string(b->second) + ")";
    const uint32_t s = set.count(id) ? set[id] : 0;

    if (storage == spv::ClassUniformConstant) {
      // Images and samplers: cube k at first_cube + k, one sampler at sampler_binding.
      const bool is_sampler = samplers.count(pointee) > 0;
      const auto si = sampled_images.find(pointee);
      const bool is_combined = si != sampled_images.end();
      const auto image = images.find(is_combined ? si->second : pointee);
      if (arrays.count(pointee)) {
        fail(where + at + " is an array of images or samplers; run() binds one cube texture per binding");
      }
      if (!is_sampler && image == images.end()) {
        fail(where + at + " is an opaque resource run() does not bind (only cube textures and their sampler)");
      }
      if (b == binding.end()) fail(where + " is an image or sampler without a binding decoration");
      if (s != 0) fail(where + at + " is in descriptor set " + std::to_string(s) + "; run() binds set 0 only");
      if (is_sampler) {
        sampler_vars.emplace_back(id, b->second);
        continue;
      }
      const ImageType& t = image->second;
      const std::string what = is_combined ? "combined image sampler" : "image";
      if (t.sampled == 2) {
        fail(where + at + " is a storage image; run() binds sampled cube textures only");
      }
      if (t.dim != spv::DimCube || t.arrayed != 0 || t.ms != 0) {
        fail(where + at + " is a " + (t.ms ? "multisampled " : "") + dim_name(t.dim) + (t.arrayed ? " array" : "") +
             " " + what + "; run() binds cube textures (GLSL samplerCube, HLSL TextureCube<float4>) only");
      }
      const auto fw = float_width.find(t.sampled_type);
      if (fw == float_width.end() || fw->second != 32) {
        fail(where + at + " is a cube " + what + " of non-float texels; run()'s cubes are RGBA float " +
             "(GLSL samplerCube, HLSL TextureCube<float4>)");
      }
      if (cube_count == 0) {
        fail(where + at + " is a cube texture but run() was given no cube textures");
      }
      if (b->second < first_cube) {
        fail(where + at + " is a cube texture at a storage buffer's binding; run() was given " +
             std::to_string(buffer_count) + " buffers, so the cubes are at " + binding_range(first_cube, cube_count));
      }
      if (b->second >= first_cube + cube_count) {
        fail(where + at + " is a cube texture beyond the " + cubes_given + " given to run()" +
             (b->second == sampler_binding && !is_combined
                  ? " (binding " + std::to_string(sampler_binding) + " is the sampler's)"
                  : ""));
      }
      auto& by_binding = is_combined ? combined : separate;
      if (!by_binding.emplace(b->second, id).second) {
        fail("two cube textures at binding " + std::to_string(b->second));
      }
      continue;
    }

    const bool storage_buffer =
        (storage == spv::ClassUniform && buffer_blocks.count(pointee)) || (storage == spv::ClassStorageBuffer);
    if (!storage_buffer) {
      fail(where + at +
           " is a uniform buffer (or a descriptor array); run() binds storage buffers only. In HLSL, a global "
           "outside a cbuffer goes to the $Global uniform buffer: declare push constants as "
           "[[vk::push_constant]] ConstantBuffer<T> or cbuffer");
    }
    if (b == binding.end()) fail(where + " is a buffer without a binding decoration");
    if (s != 0) fail(where + at + " is in descriptor set " + std::to_string(s) + "; run() binds set 0 only");
    if (b->second >= buffer_count) {
      fail(where + at + " is beyond the " + std::to_string(buffer_count) + " buffers given to run()" +
           (b->second < first_cube + cube_count ? " (binding " + std::to_string(b->second) + " is a cube texture's)"
                                                : ""));
    }
    if (!used.emplace(b->second, id).second) {
      fail("two buffers at binding " + std::to_string(b->second) +
           " (in HLSL, give every buffer its own register number, register(uK) or register(tK))");
    }
  }

  // The textures: one form, every cube present.
  if (!combined.empty() && !separate.empty()) {
    fail("the module mixes combined image samplers (" + std::to_string(combined.size()) + ") and separate images (" +
         std::to_string(separate.size()) +
         "); run() binds its cubes in one form: all combined (GLSL samplerCube) "
         "or all separate images with one sampler (HLSL TextureCube + SamplerState)");
  }
  const TextureForm form = !combined.empty()   ? TextureForm::combined
                           : !separate.empty() ? TextureForm::separate
                                               : TextureForm::none;
  const auto& textures = form == TextureForm::combined ? combined : separate;
  if (textures.size() != cube_count) {
    std::string missing, sampler_there;
    for (size_t k = 0; k < cube_count; ++k) {
      const auto b = static_cast<uint32_t>(first_cube + k);
      if (textures.count(b)) continue;
      missing += (missing.empty() ? "" : ", ") + std::to_string(b);
      for (const auto& [var, at] : sampler_vars) {
        if (at == b) {
          sampler_there = "; the sampler (variable %" + std::to_string(var) + ") is at binding " + std::to_string(b) +
                          ", which is a cube's when run() is given " + counted(cube_count, "cube");
        }
      }
    }
    fail("run() was given " + cubes_given + " but the module declares " +
         (textures.empty() ? std::string("none") : std::to_string(textures.size())) + ": no cube texture at binding " +
         missing + sampler_there + " (note: glslang's HLSL front end drops a texture the shader never samples)");
  }
  if (form == TextureForm::combined && !sampler_vars.empty()) {
    fail("variable %" + std::to_string(sampler_vars[0].first) + " (binding " + std::to_string(sampler_vars[0].second) +
         ") is a separate sampler beside combined image samplers; run() binds a sampler only for separate images");
  }
  if (form == TextureForm::none && !sampler_vars.empty()) {
    fail("variable %" + std::to_string(sampler_vars[0].first) + " (binding " + std::to_string(sampler_vars[0].second) +
         ") is a sampler but run() was given no cube textures");
  }
  if (form == TextureForm::separate) {
    const std::string declare = "declare one SamplerState at binding " + std::to_string(sampler_binding) +
                                ", e.g. [[vk::binding(" + std::to_string(sampler_binding) +
                                ", 0)]] SamplerState bands_sampler;";
    if (sampler_vars.empty()) {
      fail("the module's cube textures are separate images (HLSL TextureCube) but it has no sampler: " + declare +
           " (and sample with it: glslang removes an unused one)");
    }
    if (sampler_vars.size() > 1) {
      fail("the module declares " + std::to_string(sampler_vars.size()) +
           " samplers; run() binds one, shared by all cubes: " + declare);
    }
    if (sampler_vars[0].second != sampler_binding) {
      fail("variable %" + std::to_string(sampler_vars[0].first) + " (binding " +
           std::to_string(sampler_vars[0].second) + ") is the sampler, but with " + counted(buffer_count, "buffer") +
           " and " + counted(cube_count, "cube") + " run() binds it at binding " + std::to_string(sampler_binding) +
           ": " + declare);
    }
  }
  return form;
}

// A zeroed create-info with its sType: brace-initialising only the sType trips
// -Wmissing-field-initializers.
template <typename T>
T vk_struct(VkStructureType type) {
  T value{};
  value.sType = type;
  return value;
}

// ---------------------------------------------------------------------------------------
// Per-run Vulkan objects, destroyed in reverse order of creation by scope.

template <typename H, void (*Destroy)(VkDevice, H, const VkAllocationCallbacks*)>
class Owned {
 public:
  explicit Owned(VkDevice device) : device_(device) {}
  ~Owned() {
    if (handle_ != VK_NULL_HANDLE) Destroy(device_, handle_, nullptr);
  }
  Owned(Owned&& o) noexcept : device_(o.device_), handle_(std::exchange(o.handle_, VK_NULL_HANDLE)) {}
  Owned(const Owned&) = delete;
  Owned& operator=(const Owned&) = delete;
  Owned& operator=(Owned&&) = delete;

  H get() const { return handle_; }
  H* out() { return &handle_; }

 private:
  VkDevice device_;
  H handle_ = VK_NULL_HANDLE;
};

// The first memory type among `bits` with all of `want`; memory.memoryTypeCount if none.
uint32_t find_memory_type(const VkPhysicalDeviceMemoryProperties& memory, uint32_t bits, VkMemoryPropertyFlags want) {
  for (uint32_t t = 0; t < memory.memoryTypeCount; ++t) {
    if ((bits & (1u << t)) && (memory.memoryTypes[t].propertyFlags & want) == want) return t;
  }
  return memory.memoryTypeCount;
}

// Cube textures: RGBA float, one mip level, six layers.
constexpr VkFormat kCubeFormat = VK_FORMAT_R32G32B32A32_SFLOAT;
constexpr VkDeviceSize kCubeTexelBytes = 4 * sizeof(float);

// ---------------------------------------------------------------------------------------
// Sanitizer builds: Mesa's driver still owns heap blocks when the loader unloads it at
// vkDestroyInstance, and LeakSanitizer, which runs after that, reports them as leaks of an
// "<unknown module>" (so no suppression can name them). Keeping every library the
// instance loaded in memory until exit leaves them reachable, so only real leaks remain.

#if defined(__SANITIZE_ADDRESS__)
#define SHTOOL_PIN_VULKAN_DRIVERS 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SHTOOL_PIN_VULKAN_DRIVERS 1
#endif
#endif

#ifdef SHTOOL_PIN_VULKAN_DRIVERS
std::set<std::string> loaded_libraries() {
  std::set<std::string> names;
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void* out) {
        if (info->dlpi_name && info->dlpi_name[0]) static_cast<std::set<std::string>*>(out)->insert(info->dlpi_name);
        return 0;
      },
      &names);
  return names;
}

void pin_libraries_loaded_since(const std::set<std::string>& before) {
  for (const std::string& name : loaded_libraries()) {
    // RTLD_NOLOAD: only marks the loaded library NODELETE; the handle is left open on purpose.
    if (!before.count(name)) dlopen(name.c_str(), RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
  }
}
#endif

}  // namespace

// ---------------------------------------------------------------------------------------

std::vector<uint32_t> compile_compute(const std::string& source, ShaderLanguage lang, std::string* log) {
  ScratchFiles files;
  const bool hlsl = lang == ShaderLanguage::hlsl;
  const fs::path src = files.make(hlsl ? ".hlsl" : ".comp");
  const fs::path spv = files.make(".spv");
  const fs::path out = files.make(".log");
  write_bytes(src, source.data(), source.size());

  std::vector<std::string> argv = {SHTOOL_GLSLANG_VALIDATOR, "-V", "--target-env", "vulkan1.0", "-S", "comp"};
  if (hlsl) argv.insert(argv.end(), {"-D", "-e", "main"});
  argv.insert(argv.end(), {src.string(), "-o", spv.string()});
  const int rc = run_tool(argv, out);
  const std::string output = read_text(out);
  if (log) *log = output;

  std::vector<uint32_t> words;
  std::string problem;
  if (rc != 0) {
    problem = "exit code " + std::to_string(rc);
  } else {
    const std::string bytes = read_text(spv);
    words.resize(bytes.size() / 4);
    if (!words.empty()) std::memcpy(words.data(), bytes.data(), words.size() * 4);
    if (bytes.size() % 4 != 0 || words.size() < 5 || words[0] != spv::kMagic) problem = "no valid .spv written";
  }
  if (!problem.empty()) {
    throw std::runtime_error(std::string("glslangValidator failed (") + problem + ") on a " + (hlsl ? "HLSL" : "GLSL") +
                             " compute shader\n$ " + command_line(argv) + "\n" + output + "--- source ---\n" +
                             numbered(source));
  }
  return words;
}

void validate_spirv(const std::vector<uint32_t>& spirv) {
  ScratchFiles files;
  const fs::path spv = files.make(".spv");
  const fs::path out = files.make(".log");
  write_bytes(spv, spirv.data(), spirv.size() * 4);
  const std::vector<std::string> argv = {SHTOOL_SPIRV_VAL, "--target-env", "vulkan1.0", spv.string()};
  const int rc = run_tool(argv, out);
  if (rc != 0) {
    throw std::runtime_error("spirv-val rejected the module (exit code " + std::to_string(rc) + ")\n$ " +
                             command_line(argv) + "\n" + read_text(out));
  }
}

bool gpu_tests_skipped_by_request() {
  const char* v = std::getenv("SHTOOL_SKIP_GPU_TESTS");
  return v != nullptr && std::string(v) == "1";
}

// ---------------------------------------------------------------------------------------

std::unique_ptr<VulkanCompute> VulkanCompute::create(std::string* why_not) {
  auto reason = [&](std::string r) {
    if (why_not) *why_not = std::move(r);
    return nullptr;
  };
  std::unique_ptr<VulkanCompute> vc(new VulkanCompute());

  auto app = vk_struct<VkApplicationInfo>(VK_STRUCTURE_TYPE_APPLICATION_INFO);
  app.pApplicationName = "shtool tests";
  app.apiVersion = VK_API_VERSION_1_0;
  auto ici = vk_struct<VkInstanceCreateInfo>(VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO);
  ici.pApplicationInfo = &app;
#ifdef SHTOOL_PIN_VULKAN_DRIVERS
  const std::set<std::string> before = loaded_libraries();
#endif
  if (VkResult r = vkCreateInstance(&ici, nullptr, &vc->instance_); r != VK_SUCCESS) {
    vc->instance_ = VK_NULL_HANDLE;
    return reason("vkCreateInstance failed: " + describe(r) +
                  (r == VK_ERROR_INCOMPATIBLE_DRIVER ? " (no Vulkan driver (ICD) installed)" : ""));
  }

#ifdef SHTOOL_PIN_VULKAN_DRIVERS
  pin_libraries_loaded_since(before);
#endif

  uint32_t n = 0;
  if (VkResult r = vkEnumeratePhysicalDevices(vc->instance_, &n, nullptr); r != VK_SUCCESS) {
    return reason("vkEnumeratePhysicalDevices failed: " + describe(r));
  }
  std::vector<VkPhysicalDevice> devices(n);
  if (VkResult r = vkEnumeratePhysicalDevices(vc->instance_, &n, devices.data());
      r != VK_SUCCESS && r != VK_INCOMPLETE) {
    return reason("vkEnumeratePhysicalDevices failed: " + describe(r));
  }
  devices.resize(n);
  if (devices.empty()) return reason("the Vulkan instance has no physical devices");

  // Lower is better: the CPU device first, so every machine runs the same implementation.
  auto rank = [](VkPhysicalDeviceType t) {
    switch (t) {
      case VK_PHYSICAL_DEVICE_TYPE_CPU:
        return 0;
      case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
        return 1;
      case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
        return 2;
      case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
        return 3;
      default:
        return 4;
    }
  };
  int best_rank = 1 << 30;
  std::string seen;
  for (VkPhysicalDevice d : devices) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(d, &p);
    seen += std::string(seen.empty() ? "" : ", ") + p.deviceName;
    uint32_t qn = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(d, &qn, nullptr);
    std::vector<VkQueueFamilyProperties> families(qn);
    vkGetPhysicalDeviceQueueFamilyProperties(d, &qn, families.data());
    for (uint32_t q = 0; q < qn; ++q) {
      if ((families[q].queueFlags & VK_QUEUE_COMPUTE_BIT) && families[q].queueCount > 0 &&
          rank(p.deviceType) < best_rank) {
        best_rank = rank(p.deviceType);
        vc->physical_ = d;
        vc->queue_family_ = q;
        vc->properties_ = p;
        break;
      }
    }
  }
  if (vc->physical_ == VK_NULL_HANDLE) return reason("no Vulkan device with a compute queue (devices: " + seen + ")");
  vkGetPhysicalDeviceMemoryProperties(vc->physical_, &vc->memory_);

  const float priority = 1.0f;
  auto qci = vk_struct<VkDeviceQueueCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO);
  qci.queueFamilyIndex = vc->queue_family_;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  auto dci = vk_struct<VkDeviceCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO);
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  if (VkResult r = vkCreateDevice(vc->physical_, &dci, nullptr, &vc->device_); r != VK_SUCCESS) {
    vc->device_ = VK_NULL_HANDLE;
    return reason(std::string("vkCreateDevice failed on ") + vc->properties_.deviceName + ": " + describe(r));
  }
  vkGetDeviceQueue(vc->device_, vc->queue_family_, 0, &vc->queue_);
  return vc;
}

VulkanCompute::~VulkanCompute() {
  if (device_ != VK_NULL_HANDLE) {
    vkDeviceWaitIdle(device_);
    vkDestroyDevice(device_, nullptr);
  }
  if (instance_ != VK_NULL_HANDLE) vkDestroyInstance(instance_, nullptr);
}

std::string VulkanCompute::device_name() const { return properties_.deviceName; }

void VulkanCompute::run(const std::vector<uint32_t>& spirv, std::vector<std::vector<float>>& buffers,
                        uint32_t invocations, const void* push_constants, uint32_t push_size) {
  run(spirv, buffers, invocations, push_constants, push_size, {});
}

void VulkanCompute::run(const std::vector<uint32_t>& spirv, std::vector<std::vector<float>>& buffers,
                        uint32_t invocations, const void* push_constants, uint32_t push_size,
                        const std::vector<CubeTexture>& cubes) {
  const VkPhysicalDeviceLimits& limits = properties_.limits;
  if (push_size > std::min(kMaxPushSize, limits.maxPushConstantsSize) || push_size % 4 != 0) {
    throw std::runtime_error("VulkanCompute::run: push_size " + std::to_string(push_size) +
                             " is not a multiple of 4 up to " + std::to_string(kMaxPushSize));
  }
  if (push_size > 0 && push_constants == nullptr) {
    throw std::runtime_error("VulkanCompute::run: push_size > 0 but push_constants is null");
  }
  const uint32_t groups = invocations / kLocalSize + (invocations % kLocalSize != 0);
  if (groups > limits.maxComputeWorkGroupCount[0]) {
    throw std::runtime_error("VulkanCompute::run: " + std::to_string(groups) + " work groups exceed the device's " +
                             std::to_string(limits.maxComputeWorkGroupCount[0]));
  }
  const auto count = static_cast<uint32_t>(buffers.size());
  const auto cube_count = static_cast<uint32_t>(cubes.size());

  // The cubes' sizes, and what the device can do with them, before anything is created.
  std::vector<VkDeviceSize> cube_offsets(cube_count);  // in the staging buffer
  VkDeviceSize staging_size = 0;
  for (uint32_t k = 0; k < cube_count; ++k) {
    const CubeTexture& cube = cubes[k];
    const std::string which = "VulkanCompute::run: cube " + std::to_string(k);
    if (cube.size < 1) throw std::runtime_error(which + " has size " + std::to_string(cube.size) + "; at least 1");
    if (static_cast<uint32_t>(cube.size) > limits.maxImageDimensionCube) {
      throw std::runtime_error(which + " has size " + std::to_string(cube.size) +
                               ", more than the device's maxImageDimensionCube " +
                               std::to_string(limits.maxImageDimensionCube));
    }
    const size_t side = static_cast<size_t>(cube.size);
    const size_t want = 6 * side * side * 4;
    if (cube.texels.size() != want) {
      throw std::runtime_error(which + " of size " + std::to_string(cube.size) + " has " +
                               std::to_string(cube.texels.size()) + " floats; 6 faces x " + std::to_string(side) +
                               " x " + std::to_string(side) + " texels x 4 channels = " + std::to_string(want));
    }
    cube_offsets[k] = staging_size;
    staging_size += want * sizeof(float);
  }
  if (cube_count > 0) {
    VkFormatProperties fp;
    vkGetPhysicalDeviceFormatProperties(physical_, kCubeFormat, &fp);
    const VkFormatFeatureFlags need =
        VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT;
    if ((fp.optimalTilingFeatures & need) != need) {
      throw std::runtime_error(std::string("VulkanCompute::run: ") + properties_.deviceName +
                               " cannot sample VK_FORMAT_R32G32B32A32_SFLOAT images with linear filtering in "
                               "optimal tiling (VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT missing), which "
                               "the cube textures need");
    }
    if (cube_count > limits.maxPerStageDescriptorSampledImages || cube_count > limits.maxDescriptorSetSampledImages ||
        cube_count > limits.maxPerStageDescriptorSamplers) {
      throw std::runtime_error(
          "VulkanCompute::run: " + std::to_string(cube_count) +
          " cube textures exceed the device's per-stage limit of " +
          std::to_string(std::min(limits.maxPerStageDescriptorSampledImages, limits.maxPerStageDescriptorSamplers)));
    }
  }
  const TextureForm form = check_interface(spirv, count, cube_count, push_size);

  // Buffers, each in its own host-visible coherent allocation: a test dispatch touches a
  // handful, and coherent memory needs no flushes around the submission.
  const VkMemoryPropertyFlags host_coherent =
      VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  // A buffer of `size` bytes for `usage` in its own host-visible coherent memory, mapped:
  // freeing the memory unmaps it, so no unmap is needed on any exit path. `what` names the
  // buffer in the error without a memory type, `call_suffix` in the failed calls.
  auto host_buffer = [&](VkDeviceSize size, VkBufferUsageFlags usage, Owned<VkBuffer, vkDestroyBuffer>& buffer,
                         Owned<VkDeviceMemory, vkFreeMemory>& memory, const std::string& what,
                         const std::string& call_suffix) {
    auto bci = vk_struct<VkBufferCreateInfo>(VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO);
    bci.size = size;
    bci.usage = usage;
    bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    check(vkCreateBuffer(device_, &bci, nullptr, buffer.out()), ("vkCreateBuffer" + call_suffix).c_str());
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(device_, buffer.get(), &req);
    const uint32_t type = find_memory_type(memory_, req.memoryTypeBits, host_coherent);
    if (type == memory_.memoryTypeCount) {
      throw std::runtime_error("VulkanCompute::run: no host-visible coherent memory type for " + what);
    }
    auto mai = vk_struct<VkMemoryAllocateInfo>(VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO);
    mai.allocationSize = req.size;
    mai.memoryTypeIndex = type;
    check(vkAllocateMemory(device_, &mai, nullptr, memory.out()), ("vkAllocateMemory" + call_suffix).c_str());
    check(vkBindBufferMemory(device_, buffer.get(), memory.get(), 0), ("vkBindBufferMemory" + call_suffix).c_str());
    void* data = nullptr;
    check(vkMapMemory(device_, memory.get(), 0, VK_WHOLE_SIZE, 0, &data), ("vkMapMemory" + call_suffix).c_str());
    return data;
  };
  std::vector<Owned<VkBuffer, vkDestroyBuffer>> vk_buffers;
  std::vector<Owned<VkDeviceMemory, vkFreeMemory>> memories;
  std::vector<void*> mapped(count);
  std::vector<VkDeviceSize> sizes(count);
  vk_buffers.reserve(count);
  memories.reserve(count);
  for (uint32_t k = 0; k < count; ++k) {
    sizes[k] = std::max<VkDeviceSize>(4, buffers[k].size() * sizeof(float));
    if (sizes[k] > limits.maxStorageBufferRange) {
      throw std::runtime_error("VulkanCompute::run: buffer " + std::to_string(k) + " of " + std::to_string(sizes[k]) +
                               " bytes exceeds maxStorageBufferRange " + std::to_string(limits.maxStorageBufferRange));
    }
    vk_buffers.emplace_back(device_);
    memories.emplace_back(device_);
    mapped[k] = host_buffer(sizes[k], VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, vk_buffers.back(), memories.back(),
                            "a storage buffer", "");
    std::memset(mapped[k], 0, sizes[k]);
    if (!buffers[k].empty()) std::memcpy(mapped[k], buffers[k].data(), buffers[k].size() * sizeof(float));
  }

  // Cube textures: every cube's texels in one host-visible staging buffer, copied into
  // device-local optimal-tiling images by the command buffer below, ahead of the dispatch.
  // Declared memory first, so each image and view is destroyed before its memory is freed.
  Owned<VkDeviceMemory, vkFreeMemory> staging_memory(device_);
  Owned<VkBuffer, vkDestroyBuffer> staging(device_);
  std::vector<Owned<VkDeviceMemory, vkFreeMemory>> image_memories;
  std::vector<Owned<VkImage, vkDestroyImage>> cube_images;
  std::vector<Owned<VkImageView, vkDestroyImageView>> cube_views;
  Owned<VkSampler, vkDestroySampler> sampler(device_);
  image_memories.reserve(cube_count);
  cube_images.reserve(cube_count);
  cube_views.reserve(cube_count);
  if (cube_count > 0) {
    void* data = host_buffer(staging_size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, staging, staging_memory,
                             "the staging buffer", " (staging)");
    for (uint32_t k = 0; k < cube_count; ++k) {
      std::memcpy(static_cast<char*>(data) + cube_offsets[k], cubes[k].texels.data(),
                  cubes[k].texels.size() * sizeof(float));
    }

    for (uint32_t k = 0; k < cube_count; ++k) {
      const auto side = static_cast<uint32_t>(cubes[k].size);
      auto ici = vk_struct<VkImageCreateInfo>(VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO);
      ici.flags = VK_IMAGE_CREATE_CUBE_COMPATIBLE_BIT;
      ici.imageType = VK_IMAGE_TYPE_2D;
      ici.format = kCubeFormat;
      ici.extent = {side, side, 1};
      ici.mipLevels = 1;
      ici.arrayLayers = 6;
      ici.samples = VK_SAMPLE_COUNT_1_BIT;
      ici.tiling = VK_IMAGE_TILING_OPTIMAL;
      ici.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
      ici.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
      ici.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
      image_memories.emplace_back(device_);
      cube_images.emplace_back(device_);
      check(vkCreateImage(device_, &ici, nullptr, cube_images.back().out()), "vkCreateImage (cube)");

      VkMemoryRequirements ireq;
      vkGetImageMemoryRequirements(device_, cube_images.back().get(), &ireq);
      uint32_t itype = find_memory_type(memory_, ireq.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
      if (itype == memory_.memoryTypeCount) itype = find_memory_type(memory_, ireq.memoryTypeBits, 0);
      if (itype == memory_.memoryTypeCount) {
        throw std::runtime_error("VulkanCompute::run: no memory type for a cube image");
      }
      auto imai = vk_struct<VkMemoryAllocateInfo>(VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO);
      imai.allocationSize = ireq.size;
      imai.memoryTypeIndex = itype;
      check(vkAllocateMemory(device_, &imai, nullptr, image_memories.back().out()), "vkAllocateMemory (cube)");
      check(vkBindImageMemory(device_, cube_images.back().get(), image_memories.back().get(), 0),
            "vkBindImageMemory (cube)");

      auto ivci = vk_struct<VkImageViewCreateInfo>(VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO);
      ivci.image = cube_images.back().get();
      ivci.viewType = VK_IMAGE_VIEW_TYPE_CUBE;
      ivci.format = kCubeFormat;
      ivci.components = {VK_COMPONENT_SWIZZLE_IDENTITY, VK_COMPONENT_SWIZZLE_IDENTITY, VK_COMPONENT_SWIZZLE_IDENTITY,
                         VK_COMPONENT_SWIZZLE_IDENTITY};
      ivci.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 6};
      cube_views.emplace_back(device_);
      check(vkCreateImageView(device_, &ivci, nullptr, cube_views.back().out()), "vkCreateImageView (cube)");
    }

    // Linear filtering within the one mip level, clamped to the edge (which seamless
    // cube filtering makes moot). vk_struct zeroes the rest: nearest mip selection, no LOD
    // bias, anisotropy or depth comparison, LOD 0 to 0, normalised coordinates.
    auto sci = vk_struct<VkSamplerCreateInfo>(VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO);
    sci.magFilter = sci.minFilter = VK_FILTER_LINEAR;
    sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    check(vkCreateSampler(device_, &sci, nullptr, sampler.out()), "vkCreateSampler");
  }

  Owned<VkShaderModule, vkDestroyShaderModule> module(device_);
  auto smci = vk_struct<VkShaderModuleCreateInfo>(VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO);
  smci.codeSize = spirv.size() * sizeof(uint32_t);
  smci.pCode = spirv.data();
  check(vkCreateShaderModule(device_, &smci, nullptr, module.out()), "vkCreateShaderModule");

  // Set 0: the buffers at 0..B-1, the cubes at B..B+C-1 (combined image samplers or
  // sampled images, as the module declares them), and for sampled images the sampler at B+C.
  const VkDescriptorType cube_type =
      form == TextureForm::separate ? VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE : VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  const bool separate_sampler = form == TextureForm::separate;
  std::vector<VkDescriptorSetLayoutBinding> bindings;
  for (uint32_t k = 0; k < count; ++k) {
    bindings.push_back({k, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
  }
  for (uint32_t k = 0; k < cube_count; ++k) {
    bindings.push_back({count + k, cube_type, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
  }
  if (separate_sampler) {
    bindings.push_back({count + cube_count, VK_DESCRIPTOR_TYPE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
  }
  const auto descriptor_count = static_cast<uint32_t>(bindings.size());
  Owned<VkDescriptorSetLayout, vkDestroyDescriptorSetLayout> set_layout(device_);
  auto dslci = vk_struct<VkDescriptorSetLayoutCreateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO);
  dslci.bindingCount = descriptor_count;
  dslci.pBindings = bindings.data();
  check(vkCreateDescriptorSetLayout(device_, &dslci, nullptr, set_layout.out()), "vkCreateDescriptorSetLayout");

  const VkPushConstantRange push_range{VK_SHADER_STAGE_COMPUTE_BIT, 0, push_size};
  Owned<VkPipelineLayout, vkDestroyPipelineLayout> layout(device_);
  auto plci = vk_struct<VkPipelineLayoutCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO);
  const VkDescriptorSetLayout set_layouts[] = {set_layout.get()};
  plci.setLayoutCount = 1;
  plci.pSetLayouts = set_layouts;
  plci.pushConstantRangeCount = push_size > 0 ? 1 : 0;
  plci.pPushConstantRanges = &push_range;
  check(vkCreatePipelineLayout(device_, &plci, nullptr, layout.out()), "vkCreatePipelineLayout");

  Owned<VkPipeline, vkDestroyPipeline> pipeline(device_);
  auto cpci = vk_struct<VkComputePipelineCreateInfo>(VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO);
  cpci.stage = vk_struct<VkPipelineShaderStageCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO);
  cpci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  cpci.stage.module = module.get();
  cpci.stage.pName = "main";
  cpci.layout = layout.get();
  check(vkCreateComputePipelines(device_, VK_NULL_HANDLE, 1, &cpci, nullptr, pipeline.out()),
        "vkCreateComputePipelines");

  // A descriptor pool needs at least one pool size, so a shader without descriptors gets none.
  Owned<VkDescriptorPool, vkDestroyDescriptorPool> pool(device_);
  VkDescriptorSet descriptor_set = VK_NULL_HANDLE;
  if (descriptor_count > 0) {
    std::vector<VkDescriptorPoolSize> pool_sizes;
    if (count > 0) pool_sizes.push_back({VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, count});
    if (cube_count > 0) pool_sizes.push_back({cube_type, cube_count});
    if (separate_sampler) pool_sizes.push_back({VK_DESCRIPTOR_TYPE_SAMPLER, 1});
    auto dpci = vk_struct<VkDescriptorPoolCreateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO);
    dpci.maxSets = 1;
    dpci.poolSizeCount = static_cast<uint32_t>(pool_sizes.size());
    dpci.pPoolSizes = pool_sizes.data();
    check(vkCreateDescriptorPool(device_, &dpci, nullptr, pool.out()), "vkCreateDescriptorPool");
    auto dsai = vk_struct<VkDescriptorSetAllocateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO);
    dsai.descriptorPool = pool.get();
    dsai.descriptorSetCount = 1;
    dsai.pSetLayouts = set_layouts;
    check(vkAllocateDescriptorSets(device_, &dsai, &descriptor_set), "vkAllocateDescriptorSets");

    // Sized up front: the writes point into these.
    std::vector<VkDescriptorBufferInfo> buffer_infos(count);
    std::vector<VkDescriptorImageInfo> image_infos(cube_count + (separate_sampler ? 1 : 0));
    std::vector<VkWriteDescriptorSet> writes(descriptor_count);
    for (uint32_t k = 0; k < descriptor_count; ++k) {
      writes[k] = vk_struct<VkWriteDescriptorSet>(VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET);
      writes[k].dstSet = descriptor_set;
      writes[k].dstBinding = k;
      writes[k].descriptorCount = 1;
      writes[k].descriptorType = bindings[k].descriptorType;
    }
    for (uint32_t k = 0; k < count; ++k) {
      buffer_infos[k] = {vk_buffers[k].get(), 0, sizes[k]};
      writes[k].pBufferInfo = &buffer_infos[k];
    }
    for (uint32_t k = 0; k < cube_count; ++k) {
      image_infos[k] = {separate_sampler ? VK_NULL_HANDLE : sampler.get(), cube_views[k].get(),
                        VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
      writes[count + k].pImageInfo = &image_infos[k];
    }
    if (separate_sampler) {
      image_infos[cube_count] = {sampler.get(), VK_NULL_HANDLE, VK_IMAGE_LAYOUT_UNDEFINED};
      writes[count + cube_count].pImageInfo = &image_infos[cube_count];
    }
    vkUpdateDescriptorSets(device_, descriptor_count, writes.data(), 0, nullptr);
  }

  Owned<VkCommandPool, vkDestroyCommandPool> command_pool(device_);
  auto cpoolci = vk_struct<VkCommandPoolCreateInfo>(VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO);
  cpoolci.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
  cpoolci.queueFamilyIndex = queue_family_;
  check(vkCreateCommandPool(device_, &cpoolci, nullptr, command_pool.out()), "vkCreateCommandPool");
  VkCommandBuffer cmd = VK_NULL_HANDLE;  // freed with its pool
  auto cbai = vk_struct<VkCommandBufferAllocateInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO);
  cbai.commandPool = command_pool.get();
  cbai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cbai.commandBufferCount = 1;
  check(vkAllocateCommandBuffers(device_, &cbai, &cmd), "vkAllocateCommandBuffers");

  auto begin = vk_struct<VkCommandBufferBeginInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO);
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  check(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");
  if (cube_count > 0) {
    // UNDEFINED -> TRANSFER_DST_OPTIMAL, the copy of all six layers, then
    // TRANSFER_DST_OPTIMAL -> SHADER_READ_ONLY_OPTIMAL before the compute shader reads.
    // The submission makes the host's writes to the staging buffer visible to the copy.
    std::vector<VkImageMemoryBarrier> to_transfer(cube_count), to_shader(cube_count);
    for (uint32_t k = 0; k < cube_count; ++k) {
      auto barrier = vk_struct<VkImageMemoryBarrier>(VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER);
      barrier.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
      barrier.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
      barrier.image = cube_images[k].get();
      barrier.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 6};
      to_transfer[k] = barrier;
      to_transfer[k].srcAccessMask = 0;
      to_transfer[k].dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
      to_transfer[k].oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
      to_transfer[k].newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
      to_shader[k] = barrier;
      to_shader[k].srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
      to_shader[k].dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
      to_shader[k].oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
      to_shader[k].newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    }
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0,
                         nullptr, cube_count, to_transfer.data());
    for (uint32_t k = 0; k < cube_count; ++k) {
      // Tightly packed (row length and image height 0): layer f starts f * size * size
      // texels in, which is CubeTexture's face order and row-major layout.
      const auto side = static_cast<uint32_t>(cubes[k].size);
      VkBufferImageCopy region{};
      region.bufferOffset = cube_offsets[k];
      region.bufferRowLength = 0;
      region.bufferImageHeight = 0;
      region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 6};
      region.imageOffset = {0, 0, 0};
      region.imageExtent = {side, side, 1};
      vkCmdCopyBufferToImage(cmd, staging.get(), cube_images[k].get(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                             &region);
    }
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0, nullptr, 0,
                         nullptr, cube_count, to_shader.data());
  }
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.get());
  if (descriptor_count > 0) {
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout.get(), 0, 1, &descriptor_set, 0, nullptr);
  }
  if (push_size > 0) vkCmdPushConstants(cmd, layout.get(), VK_SHADER_STAGE_COMPUTE_BIT, 0, push_size, push_constants);
  vkCmdDispatch(cmd, groups, 1, 1);
  // The submission makes the host's writes visible to the shader; the way back needs
  // this barrier, or the fence alone would not make the shader's writes host-visible.
  auto to_host = vk_struct<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
  to_host.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  to_host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &to_host, 0,
                       nullptr, 0, nullptr);
  check(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");

  Owned<VkFence, vkDestroyFence> fence(device_);
  auto fci = vk_struct<VkFenceCreateInfo>(VK_STRUCTURE_TYPE_FENCE_CREATE_INFO);
  check(vkCreateFence(device_, &fci, nullptr, fence.out()), "vkCreateFence");
  auto submit = vk_struct<VkSubmitInfo>(VK_STRUCTURE_TYPE_SUBMIT_INFO);
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd;
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    check(vkQueueSubmit(queue_, 1, &submit, fence.get()), "vkQueueSubmit");
  }
  // No timeout: a runaway shader is the test runner's TIMEOUT to report, and giving up
  // here would destroy objects the device may still be using.
  const VkFence fences[] = {fence.get()};
  check(vkWaitForFences(device_, 1, fences, VK_TRUE, UINT64_MAX), "vkWaitForFences");

  for (uint32_t k = 0; k < count; ++k) {
    if (!buffers[k].empty()) std::memcpy(buffers[k].data(), mapped[k], buffers[k].size() * sizeof(float));
  }
}

}  // namespace shtool::gpu
