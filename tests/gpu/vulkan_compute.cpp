// The Vulkan compute harness of the GPU tests: shader compilation through the glslang and
// SPIRV-Tools executables, a minimal reflection of the module against run()'s arguments,
// and one dispatch per run() over host-visible storage buffers.
#include "vulkan_compute.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
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
constexpr uint32_t OpEntryPoint = 15, OpExecutionMode = 16, OpTypePointer = 32, OpConstant = 43,
                   OpConstantComposite = 44, OpSpecConstant = 50, OpSpecConstantComposite = 51, OpVariable = 59,
                   OpDecorate = 71, OpMemberDecorate = 72;
constexpr uint32_t ModelGLCompute = 5, ModeLocalSize = 17, ModeLocalSizeId = 38;
constexpr uint32_t DecBlock = 2, DecBufferBlock = 3, DecBuiltIn = 11, DecBinding = 33, DecDescriptorSet = 34,
                   DecOffset = 35, BuiltInWorkgroupSize = 25;
constexpr uint32_t ClassUniformConstant = 0, ClassUniform = 2, ClassPushConstant = 9, ClassStorageBuffer = 12;
}  // namespace spv

void check_interface(const std::vector<uint32_t>& code, size_t buffer_count, uint32_t push_size) {
  auto fail = [](const std::string& what) { throw std::runtime_error("VulkanCompute::run: " + what); };
  if (code.size() < 5 || code[0] != spv::kMagic) fail("not a SPIR-V module (bad size or magic number)");

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

  std::map<uint32_t, uint32_t> used;  // binding -> variable
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
    if (storage == spv::ClassUniformConstant)
      fail(where + at + " is an image or sampler; run() binds storage buffers only");
    const bool storage_buffer =
        (storage == spv::ClassUniform && buffer_blocks.count(pointee)) || (storage == spv::ClassStorageBuffer);
    if (!storage_buffer) {
      fail(where + at +
           " is a uniform buffer (or a descriptor array); run() binds storage buffers only. In HLSL, a global "
           "outside a cbuffer goes to the $Global uniform buffer: declare push constants as "
           "[[vk::push_constant]] ConstantBuffer<T> or cbuffer");
    }
    if (b == binding.end()) fail(where + " is a buffer without a binding decoration");
    const uint32_t s = set.count(id) ? set[id] : 0;
    if (s != 0) fail(where + at + " is in descriptor set " + std::to_string(s) + "; run() binds set 0 only");
    if (b->second >= buffer_count) {
      fail(where + at + " is beyond the " + std::to_string(buffer_count) + " buffers given to run()");
    }
    if (!used.emplace(b->second, id).second) {
      fail("two buffers at binding " + std::to_string(b->second) +
           " (in HLSL, give every buffer its own register number, register(uK) or register(tK))");
    }
  }
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
  check_interface(spirv, buffers.size(), push_size);
  const auto count = static_cast<uint32_t>(buffers.size());

  // Buffers, each in its own host-visible coherent allocation: a test dispatch touches a
  // handful, and coherent memory needs no flushes around the submission.
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
    auto bci = vk_struct<VkBufferCreateInfo>(VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO);
    bci.size = sizes[k];
    bci.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    vk_buffers.emplace_back(device_);
    check(vkCreateBuffer(device_, &bci, nullptr, vk_buffers.back().out()), "vkCreateBuffer");

    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(device_, vk_buffers.back().get(), &req);
    const VkMemoryPropertyFlags want = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    uint32_t type = memory_.memoryTypeCount;
    for (uint32_t t = 0; t < memory_.memoryTypeCount && type == memory_.memoryTypeCount; ++t) {
      if ((req.memoryTypeBits & (1u << t)) && (memory_.memoryTypes[t].propertyFlags & want) == want) type = t;
    }
    if (type == memory_.memoryTypeCount) {
      throw std::runtime_error("VulkanCompute::run: no host-visible coherent memory type for a storage buffer");
    }
    auto mai = vk_struct<VkMemoryAllocateInfo>(VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO);
    mai.allocationSize = req.size;
    mai.memoryTypeIndex = type;
    memories.emplace_back(device_);
    check(vkAllocateMemory(device_, &mai, nullptr, memories.back().out()), "vkAllocateMemory");
    check(vkBindBufferMemory(device_, vk_buffers.back().get(), memories.back().get(), 0), "vkBindBufferMemory");
    // Freeing the memory unmaps it: no unmap needed on any exit path.
    check(vkMapMemory(device_, memories.back().get(), 0, VK_WHOLE_SIZE, 0, &mapped[k]), "vkMapMemory");
    std::memset(mapped[k], 0, sizes[k]);
    if (!buffers[k].empty()) std::memcpy(mapped[k], buffers[k].data(), buffers[k].size() * sizeof(float));
  }

  Owned<VkShaderModule, vkDestroyShaderModule> module(device_);
  auto smci = vk_struct<VkShaderModuleCreateInfo>(VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO);
  smci.codeSize = spirv.size() * sizeof(uint32_t);
  smci.pCode = spirv.data();
  check(vkCreateShaderModule(device_, &smci, nullptr, module.out()), "vkCreateShaderModule");

  std::vector<VkDescriptorSetLayoutBinding> bindings(count);
  for (uint32_t k = 0; k < count; ++k) {
    bindings[k] = {k, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  }
  Owned<VkDescriptorSetLayout, vkDestroyDescriptorSetLayout> set_layout(device_);
  auto dslci = vk_struct<VkDescriptorSetLayoutCreateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO);
  dslci.bindingCount = count;
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

  // A descriptor pool needs at least one pool size, so a shader without buffers gets none.
  Owned<VkDescriptorPool, vkDestroyDescriptorPool> pool(device_);
  VkDescriptorSet descriptor_set = VK_NULL_HANDLE;
  if (count > 0) {
    const VkDescriptorPoolSize pool_size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, count};
    auto dpci = vk_struct<VkDescriptorPoolCreateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO);
    dpci.maxSets = 1;
    dpci.poolSizeCount = 1;
    dpci.pPoolSizes = &pool_size;
    check(vkCreateDescriptorPool(device_, &dpci, nullptr, pool.out()), "vkCreateDescriptorPool");
    auto dsai = vk_struct<VkDescriptorSetAllocateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO);
    dsai.descriptorPool = pool.get();
    dsai.descriptorSetCount = 1;
    dsai.pSetLayouts = set_layouts;
    check(vkAllocateDescriptorSets(device_, &dsai, &descriptor_set), "vkAllocateDescriptorSets");

    std::vector<VkDescriptorBufferInfo> infos(count);
    std::vector<VkWriteDescriptorSet> writes(count);
    for (uint32_t k = 0; k < count; ++k) {
      infos[k] = {vk_buffers[k].get(), 0, sizes[k]};
      writes[k] = vk_struct<VkWriteDescriptorSet>(VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET);
      writes[k].dstSet = descriptor_set;
      writes[k].dstBinding = k;
      writes[k].descriptorCount = 1;
      writes[k].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
      writes[k].pBufferInfo = &infos[k];
    }
    vkUpdateDescriptorSets(device_, count, writes.data(), 0, nullptr);
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
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.get());
  if (count > 0) {
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
