// The Vulkan layer: the loader opened with dlopen, functions fetched through
// vkGetInstanceProcAddr / vkGetDeviceProcAddr, every VkResult checked.
#define VK_NO_PROTOTYPES
#include "gpu/vulkan.hpp"

#include <dlfcn.h>
#include <vulkan/vulkan.h>

#include <algorithm>
#include <cstring>
#include <mutex>
#include <utility>

namespace penumbra::gpu {

// Functions of each level, fetched once.
#define PENUMBRA_VK_INSTANCE(X)               \
  X(vkEnumeratePhysicalDevices)               \
  X(vkGetPhysicalDeviceProperties)            \
  X(vkGetPhysicalDeviceQueueFamilyProperties) \
  X(vkGetPhysicalDeviceMemoryProperties)      \
  X(vkGetPhysicalDeviceFeatures2)             \
  X(vkCreateDevice)                           \
  X(vkGetDeviceProcAddr)

#define PENUMBRA_VK_DEVICE(X)      \
  X(vkDestroyDevice)               \
  X(vkGetDeviceQueue)              \
  X(vkCreateBuffer)                \
  X(vkDestroyBuffer)               \
  X(vkGetBufferMemoryRequirements) \
  X(vkAllocateMemory)              \
  X(vkFreeMemory)                  \
  X(vkBindBufferMemory)            \
  X(vkMapMemory)                   \
  X(vkCreateShaderModule)          \
  X(vkDestroyShaderModule)         \
  X(vkCreateDescriptorSetLayout)   \
  X(vkDestroyDescriptorSetLayout)  \
  X(vkCreatePipelineLayout)        \
  X(vkDestroyPipelineLayout)       \
  X(vkCreateComputePipelines)      \
  X(vkDestroyPipeline)             \
  X(vkCreateDescriptorPool)        \
  X(vkDestroyDescriptorPool)       \
  X(vkAllocateDescriptorSets)      \
  X(vkUpdateDescriptorSets)        \
  X(vkCreateCommandPool)           \
  X(vkDestroyCommandPool)          \
  X(vkAllocateCommandBuffers)      \
  X(vkFreeCommandBuffers)          \
  X(vkBeginCommandBuffer)          \
  X(vkEndCommandBuffer)            \
  X(vkCmdBindPipeline)             \
  X(vkCmdBindDescriptorSets)       \
  X(vkCmdPushConstants)            \
  X(vkCmdDispatch)                 \
  X(vkCmdCopyBuffer)               \
  X(vkCmdPipelineBarrier)          \
  X(vkCmdResetQueryPool)           \
  X(vkCmdWriteTimestamp)           \
  X(vkCreateQueryPool)             \
  X(vkDestroyQueryPool)            \
  X(vkGetQueryPoolResults)         \
  X(vkCreateFence)                 \
  X(vkDestroyFence)                \
  X(vkWaitForFences)               \
  X(vkQueueSubmit)

#define PENUMBRA_VK_MEMBER(name) PFN_##name name = nullptr;

struct Context::Impl {
  PFN_vkGetInstanceProcAddr vkGetInstanceProcAddr = nullptr;
  PENUMBRA_VK_INSTANCE(PENUMBRA_VK_MEMBER)
  PENUMBRA_VK_DEVICE(PENUMBRA_VK_MEMBER)
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  std::uint32_t family = 0;
  std::uint32_t memory_type = 0;         // host-visible: what the host writes and reads back
  std::uint64_t heap_bytes = 0;          // of the heap host buffers come from
  std::uint32_t device_memory_type = 0;  // device-local: what only kernels touch
  std::uint64_t device_heap_bytes = 0;
  std::uint32_t timestamp_bits = 0;
  VkCommandPool command_pool = VK_NULL_HANDLE;

  ~Impl() {
    if (device) {
      if (command_pool) vkDestroyCommandPool(device, command_pool, nullptr);
      vkDestroyDevice(device, nullptr);
    }
    // The instance is the process's (process_instance) and stays.
  }
};

namespace {

std::string result_text(VkResult r) {
  switch (r) {
    case VK_ERROR_OUT_OF_HOST_MEMORY:
      return "out of host memory";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY:
      return "out of device memory";
    case VK_ERROR_INITIALIZATION_FAILED:
      return "initialization failed";
    case VK_ERROR_DEVICE_LOST:
      return "device lost";
    case VK_ERROR_MEMORY_MAP_FAILED:
      return "memory map failed";
    case VK_ERROR_LAYER_NOT_PRESENT:
      return "layer not present";
    case VK_ERROR_EXTENSION_NOT_PRESENT:
      return "extension not present";
    case VK_ERROR_FEATURE_NOT_PRESENT:
      return "feature not present";
    case VK_ERROR_INCOMPATIBLE_DRIVER:
      return "incompatible driver (no Vulkan 1.1 driver installed?)";
    case VK_ERROR_TOO_MANY_OBJECTS:
      return "too many objects";
    case VK_ERROR_FRAGMENTED_POOL:
      return "fragmented pool";
    case VK_ERROR_OUT_OF_POOL_MEMORY:
      return "out of pool memory";
    case VK_TIMEOUT:
      return "timeout";
    default:
      return "VkResult " + std::to_string(int(r));
  }
}

Status check(VkResult r, const char* what) {
  if (r == VK_SUCCESS) return {};
  return Error{std::string("Vulkan: ") + what + " failed: " + result_text(r)};
}

const char* type_name(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
      return "discrete";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
      return "integrated";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
      return "virtual";
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
      return "cpu";
    default:
      return "other";
  }
}

// Hardware first: discrete, integrated, virtual, then other, then CPU drivers.
int rank(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
      return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
      return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
      return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
      return 4;
    default:
      return 3;
  }
}

template <class F>
F load(PFN_vkGetInstanceProcAddr get, VkInstance instance, const char* name) {
  return reinterpret_cast<F>(get(instance, name));
}

}  // namespace

namespace {

// One Vulkan instance for the whole process, made by the first create() that finds a driver and
// never destroyed. NVIDIA's driver goes wrong after repeated vkCreateInstance /
// vkDestroyInstance cycles in one process: on an H200 (driver 580) the test binary's
// vkCreateInstance answered VK_ERROR_INCOMPATIBLE_DRIVER after some hundred contexts, and the
// same case alone passed. Devices are still made and destroyed per Context.
struct ProcessInstance {
  void* library = nullptr;
  PFN_vkGetInstanceProcAddr get = nullptr;
  VkInstance instance = VK_NULL_HANDLE;
};

Expected<ProcessInstance> process_instance() {
  static std::mutex mutex;
  static ProcessInstance* made = nullptr;  // kept for the process's life on purpose
  std::lock_guard<std::mutex> lock(mutex);
  if (made) return *made;
  ProcessInstance p;
  p.library = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
  if (!p.library)
    return Error{
        "Vulkan: cannot load the Vulkan loader libvulkan.so.1 (install libvulkan1 and a "
        "driver, e.g. mesa-vulkan-drivers)"};
  auto fail = [&](Error e) -> Expected<ProcessInstance> {
    dlclose(p.library);
    return e;
  };
  p.get = reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(p.library, "vkGetInstanceProcAddr"));
  if (!p.get) return fail(Error{"Vulkan: the loader has no vkGetInstanceProcAddr"});
  const auto create_instance =
      load<PFN_vkCreateInstance>(p.get, VK_NULL_HANDLE, "vkCreateInstance");
  if (!create_instance) return fail(Error{"Vulkan: the loader has no vkCreateInstance"});

  VkApplicationInfo app{};
  app.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO;
  app.pApplicationName = "penumbra";
  app.pEngineName = "penumbra";
  app.apiVersion = VK_API_VERSION_1_1;
  VkInstanceCreateInfo ici{};
  ici.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO;
  ici.pApplicationInfo = &app;
  const VkResult created = create_instance(&ici, nullptr, &p.instance);
  if (created == VK_ERROR_INCOMPATIBLE_DRIVER)  // what the loader says when it finds no driver
    return fail(
        Error{"Vulkan: no Vulkan 1.1 driver found (install your GPU's driver, or "
              "mesa-vulkan-drivers for lavapipe, the CPU driver)"});
  if (Status s = check(created, "creating the instance"); !s) return fail(s.error());
  made = new ProcessInstance(p);
  return p;
}

}  // namespace

Expected<std::shared_ptr<Context>> Context::create(bool allow_cpu) {
  std::shared_ptr<Context> c(new Context);
  c->impl_ = std::make_unique<Impl>();
  Impl& v = *c->impl_;
  Expected<ProcessInstance> shared = process_instance();
  if (!shared) return shared.error();
  v.vkGetInstanceProcAddr = shared->get;
  v.instance = shared->instance;
#define PENUMBRA_VK_LOAD_INSTANCE(name)                                  \
  v.name = load<PFN_##name>(v.vkGetInstanceProcAddr, v.instance, #name); \
  if (!v.name) return Error{"Vulkan: the instance has no " #name};
  PENUMBRA_VK_INSTANCE(PENUMBRA_VK_LOAD_INSTANCE)
#undef PENUMBRA_VK_LOAD_INSTANCE

  std::uint32_t count = 0;
  if (Status s =
          check(v.vkEnumeratePhysicalDevices(v.instance, &count, nullptr), "listing the devices");
      !s)
    return s.error();
  std::vector<VkPhysicalDevice> devices(count);
  if (count > 0)
    if (Status s = check(v.vkEnumeratePhysicalDevices(v.instance, &count, devices.data()),
                         "listing the devices");
        !s)
      return s.error();
  // The best-ranked device with a compute queue and host-visible coherent memory.
  int best_rank = 99;
  std::string seen;
  for (VkPhysicalDevice d : devices) {
    VkPhysicalDeviceProperties p;
    v.vkGetPhysicalDeviceProperties(d, &p);
    seen +=
        std::string(seen.empty() ? "" : ", ") + p.deviceName + " (" + type_name(p.deviceType) + ")";
    if (p.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU && !allow_cpu) continue;
    if (p.apiVersion < VK_API_VERSION_1_1) continue;
    std::uint32_t families = 0;
    v.vkGetPhysicalDeviceQueueFamilyProperties(d, &families, nullptr);
    std::vector<VkQueueFamilyProperties> fp(families);
    v.vkGetPhysicalDeviceQueueFamilyProperties(d, &families, fp.data());
    int family = -1;
    for (std::uint32_t i = 0; i < families && family < 0; ++i)
      if (fp[i].queueFlags & VK_QUEUE_COMPUTE_BIT) family = int(i);
    if (family < 0) continue;
    VkPhysicalDeviceMemoryProperties mp;
    v.vkGetPhysicalDeviceMemoryProperties(d, &mp);
    const VkMemoryPropertyFlags want =
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    // The host-visible coherent type for uploads and read-back: cached first, then the
    // largest heap. Uncached host-visible memory on a discrete GPU is its BAR, device memory
    // behind PCIe: the CPU reads it at tens of MB/s (on an H200 reading a 2048^2 fluence back
    // took 2.3 s), and without resizable BAR it is a 256 MiB window that holds only small
    // grids. Cached system memory reads back at memory speed.
    int type = -1;
    auto heap_of = [&](int i) { return mp.memoryHeaps[mp.memoryTypes[i].heapIndex].size; };
    auto cached = [&](int i) {
      return (mp.memoryTypes[i].propertyFlags & VK_MEMORY_PROPERTY_HOST_CACHED_BIT) != 0;
    };
    for (std::uint32_t i = 0; i < mp.memoryTypeCount; ++i) {
      const VkMemoryPropertyFlags f = mp.memoryTypes[i].propertyFlags;
      if ((f & want) != want) continue;
      if (type < 0 || (cached(int(i)) && !cached(type)) ||
          (cached(int(i)) == cached(type) && heap_of(int(i)) > heap_of(type)))
        type = int(i);
    }
    if (type < 0) continue;
    if (rank(p.deviceType) >= best_rank) continue;
    // Working buffers: device-local memory on the largest such heap (on a discrete GPU the
    // host-visible heap may be system memory behind PCIe); the host type where there is none.
    int local = -1;
    for (std::uint32_t i = 0; i < mp.memoryTypeCount; ++i)
      if ((mp.memoryTypes[i].propertyFlags & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) &&
          (local < 0 || heap_of(int(i)) > heap_of(local)))
        local = int(i);
    if (local < 0) local = type;
    v.device_memory_type = std::uint32_t(local);
    v.device_heap_bytes = heap_of(local);
    v.heap_bytes = mp.memoryHeaps[mp.memoryTypes[type].heapIndex].size;
    best_rank = rank(p.deviceType);
    v.physical = d;
    v.family = std::uint32_t(family);
    v.memory_type = std::uint32_t(type);
    DeviceInfo& info = c->info_;
    info.name = p.deviceName;
    info.type = type_name(p.deviceType);
    info.cpu = p.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
    info.timestamp_period_ns =
        fp[std::size_t(family)].timestampValidBits > 0 ? double(p.limits.timestampPeriod) : 0.0;
    info.max_workgroups_x = p.limits.maxComputeWorkGroupCount[0];
    info.max_workgroups_y = p.limits.maxComputeWorkGroupCount[1];
    info.max_buffer_bytes = p.limits.maxStorageBufferRange;
    info.offset_alignment = std::max<std::uint64_t>(p.limits.minStorageBufferOffsetAlignment, 1);
    v.timestamp_bits = fp[std::size_t(family)].timestampValidBits;
    info.device_local_bytes = 0;
    for (std::uint32_t h = 0; h < mp.memoryHeapCount; ++h)
      if (mp.memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT)
        info.device_local_bytes += mp.memoryHeaps[h].size;
  }
  if (!v.physical) {
    if (seen.empty()) return Error{"Vulkan: no device (no Vulkan driver is installed)"};
    return Error{std::string("Vulkan: no suitable device among: ") + seen +
                 (allow_cpu ? "" : " (CPU drivers are not used here)")};
  }

  const float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{};
  qci.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO;
  qci.queueFamilyIndex = v.family;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  VkDeviceCreateInfo dci{};
  dci.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO;
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  // 16-bit floats in storage buffers (HRC's --storage f16), where the device has them.
  VkPhysicalDevice16BitStorageFeatures storage16{};
  storage16.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_16BIT_STORAGE_FEATURES;
  VkPhysicalDeviceFeatures2 features{};
  features.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2;
  features.pNext = &storage16;
  v.vkGetPhysicalDeviceFeatures2(v.physical, &features);
  VkPhysicalDevice16BitStorageFeatures enable16{};
  enable16.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_16BIT_STORAGE_FEATURES;
  enable16.storageBuffer16BitAccess = storage16.storageBuffer16BitAccess;
  c->info_.storage_f16 = storage16.storageBuffer16BitAccess == VK_TRUE;
  dci.pNext = &enable16;
  if (Status s =
          check(v.vkCreateDevice(v.physical, &dci, nullptr, &v.device), "creating the device");
      !s)
    return s.error();
#define PENUMBRA_VK_LOAD_DEVICE(name)                                            \
  v.name = reinterpret_cast<PFN_##name>(v.vkGetDeviceProcAddr(v.device, #name)); \
  if (!v.name) return Error{"Vulkan: the device has no " #name};
  PENUMBRA_VK_DEVICE(PENUMBRA_VK_LOAD_DEVICE)
#undef PENUMBRA_VK_LOAD_DEVICE
  v.vkGetDeviceQueue(v.device, v.family, 0, &v.queue);
  VkCommandPoolCreateInfo pci{};
  pci.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO;
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = v.family;
  if (Status s = check(v.vkCreateCommandPool(v.device, &pci, nullptr, &v.command_pool),
                       "creating a command pool");
      !s)
    return s.error();
  return c;
}

Context::~Context() = default;

// ---- buffers ------------------------------------------------------------------------------

Buffer::~Buffer() {
  release();
}
Buffer::Buffer(Buffer&& o) noexcept {
  *this = std::move(o);
}
Buffer& Buffer::operator=(Buffer&& o) noexcept {
  if (this != &o) {
    release();
    std::swap(context_, o.context_);
    std::swap(buffer_, o.buffer_);
    std::swap(memory_, o.memory_);
    std::swap(bytes_, o.bytes_);
    std::swap(mapped_, o.mapped_);
  }
  return *this;
}
void Buffer::release() {
  if (!context_) return;
  const Context::Impl& v = context_->impl();
  if (buffer_) v.vkDestroyBuffer(v.device, reinterpret_cast<VkBuffer>(buffer_), nullptr);
  if (memory_) v.vkFreeMemory(v.device, reinterpret_cast<VkDeviceMemory>(memory_), nullptr);
  context_ = nullptr;
  buffer_ = memory_ = 0;
  mapped_ = nullptr;
}

Expected<Buffer> Context::buffer(std::size_t bytes, Memory where, bool in_pieces) const {
  const Impl& v = *impl_;
  const bool host = where == Memory::host;
  const std::uint64_t heap = host ? v.heap_bytes : v.device_heap_bytes;
  const std::uint32_t memory_type = host ? v.memory_type : v.device_memory_type;
  // Refused before the driver sees it: a storage buffer cannot be bound past the device's
  // range, and larger than the whole heap cannot succeed.
  if (bytes > info_.max_buffer_bytes && !in_pieces)
    return Error{"Vulkan: a buffer of " + std::to_string(bytes >> 20) + " MiB is larger than " +
                 info_.name + " can bind (" + std::to_string(info_.max_buffer_bytes >> 20) +
                 " MiB); use a smaller grid or `device` cpu"};
  if (bytes > heap)
    return Error{"Vulkan: a buffer of " + std::to_string(bytes >> 20) + " MiB is larger than " +
                 info_.name + "'s memory heap (" + std::to_string(heap >> 20) + " MiB)"};
  Buffer b;
  b.context_ = this;
  b.bytes_ = bytes;
  VkBufferCreateInfo bci{};
  bci.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
  bci.size = std::max<std::size_t>(bytes, 4);
  bci.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
              VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkBuffer buffer = VK_NULL_HANDLE;
  if (Status s = check(v.vkCreateBuffer(v.device, &bci, nullptr, &buffer), "creating a buffer"); !s)
    return s.error();
  b.buffer_ = reinterpret_cast<std::uint64_t>(buffer);
  VkMemoryRequirements req;
  v.vkGetBufferMemoryRequirements(v.device, buffer, &req);
  if (!(req.memoryTypeBits & (1u << memory_type)))
    return Error{std::string("Vulkan: a buffer cannot live in the chosen ") +
                 (host ? "host-visible" : "device-local") + " memory"};
  VkMemoryAllocateInfo mai{};
  mai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = memory_type;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  if (Status s = check(v.vkAllocateMemory(v.device, &mai, nullptr, &memory),
                       ("allocating " + std::to_string(bytes) + " bytes").c_str());
      !s)
    return s.error();
  b.memory_ = reinterpret_cast<std::uint64_t>(memory);
  if (Status s = check(v.vkBindBufferMemory(v.device, buffer, memory, 0), "binding memory"); !s)
    return s.error();
  if (host)
    if (Status s = check(v.vkMapMemory(v.device, memory, 0, VK_WHOLE_SIZE, 0, &b.mapped_),
                         "mapping memory");
        !s)
      return s.error();
  return b;
}

// ---- kernels ------------------------------------------------------------------------------

Kernel::~Kernel() {
  release();
}
Kernel::Kernel(Kernel&& o) noexcept {
  *this = std::move(o);
}
Kernel& Kernel::operator=(Kernel&& o) noexcept {
  if (this != &o) {
    release();
    std::swap(context_, o.context_);
    std::swap(name_, o.name_);
    std::swap(buffers_, o.buffers_);
    std::swap(push_bytes_, o.push_bytes_);
    std::swap(module_, o.module_);
    std::swap(set_layout_, o.set_layout_);
    std::swap(layout_, o.layout_);
    std::swap(pipeline_, o.pipeline_);
  }
  return *this;
}
void Kernel::release() {
  if (!context_) return;
  const Context::Impl& v = context_->impl();
  if (pipeline_) v.vkDestroyPipeline(v.device, reinterpret_cast<VkPipeline>(pipeline_), nullptr);
  if (layout_)
    v.vkDestroyPipelineLayout(v.device, reinterpret_cast<VkPipelineLayout>(layout_), nullptr);
  if (set_layout_)
    v.vkDestroyDescriptorSetLayout(v.device, reinterpret_cast<VkDescriptorSetLayout>(set_layout_),
                                   nullptr);
  if (module_)
    v.vkDestroyShaderModule(v.device, reinterpret_cast<VkShaderModule>(module_), nullptr);
  context_ = nullptr;
  module_ = set_layout_ = layout_ = pipeline_ = 0;
}

Expected<Kernel> Context::kernel(const std::string& name, std::span<const std::uint32_t> spirv,
                                 int buffers, std::uint32_t push_bytes) const {
  const Impl& v = *impl_;
  Kernel k;
  k.context_ = this;
  k.name_ = name;
  k.buffers_ = buffers;
  k.push_bytes_ = push_bytes;
  const std::string what = "building kernel " + name;
  VkShaderModuleCreateInfo smci{};
  smci.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO;
  smci.codeSize = spirv.size_bytes();
  smci.pCode = spirv.data();
  VkShaderModule module = VK_NULL_HANDLE;
  if (Status s = check(v.vkCreateShaderModule(v.device, &smci, nullptr, &module), what.c_str()); !s)
    return s.error();
  k.module_ = reinterpret_cast<std::uint64_t>(module);
  std::vector<VkDescriptorSetLayoutBinding> bindings{std::size_t(buffers)};
  for (int i = 0; i < buffers; ++i) {
    bindings[std::size_t(i)] = {};
    bindings[std::size_t(i)].binding = std::uint32_t(i);
    bindings[std::size_t(i)].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    bindings[std::size_t(i)].descriptorCount = 1;
    bindings[std::size_t(i)].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
  }
  VkDescriptorSetLayoutCreateInfo dslci{};
  dslci.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO;
  dslci.bindingCount = std::uint32_t(buffers);
  dslci.pBindings = bindings.data();
  VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
  if (Status s = check(v.vkCreateDescriptorSetLayout(v.device, &dslci, nullptr, &set_layout),
                       what.c_str());
      !s)
    return s.error();
  k.set_layout_ = reinterpret_cast<std::uint64_t>(set_layout);
  VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, push_bytes};
  VkPipelineLayoutCreateInfo plci{};
  plci.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO;
  plci.setLayoutCount = 1;
  plci.pSetLayouts = &set_layout;
  plci.pushConstantRangeCount = push_bytes > 0 ? 1 : 0;
  plci.pPushConstantRanges = &range;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  if (Status s = check(v.vkCreatePipelineLayout(v.device, &plci, nullptr, &layout), what.c_str());
      !s)
    return s.error();
  k.layout_ = reinterpret_cast<std::uint64_t>(layout);
  VkComputePipelineCreateInfo cpci{};
  cpci.sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO;
  cpci.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  cpci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  cpci.stage.module = module;
  cpci.stage.pName = "main";
  cpci.layout = layout;
  VkPipeline pipeline = VK_NULL_HANDLE;
  if (Status s =
          check(v.vkCreateComputePipelines(v.device, VK_NULL_HANDLE, 1, &cpci, nullptr, &pipeline),
                what.c_str());
      !s)
    return s.error();
  k.pipeline_ = reinterpret_cast<std::uint64_t>(pipeline);
  return k;
}

// ---- batches ------------------------------------------------------------------------------

constexpr std::uint32_t kMaxDispatches = 1024;
constexpr std::uint32_t kMaxBindings = 16;

Expected<Batch> Context::batch(std::uint32_t max_passes) const {
  const Impl& v = *impl_;
  Batch b(this);
  VkCommandBufferAllocateInfo cbai{};
  cbai.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
  cbai.commandPool = v.command_pool;
  cbai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cbai.commandBufferCount = 1;
  VkCommandBuffer cb = VK_NULL_HANDLE;
  if (Status s = check(v.vkAllocateCommandBuffers(v.device, &cbai, &cb), "allocating commands"); !s)
    return s.error();
  b.command_buffer_ = reinterpret_cast<std::uint64_t>(cb);
  VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kMaxDispatches * kMaxBindings};
  VkDescriptorPoolCreateInfo dpci{};
  dpci.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO;
  dpci.maxSets = kMaxDispatches;
  dpci.poolSizeCount = 1;
  dpci.pPoolSizes = &size;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  if (Status s = check(v.vkCreateDescriptorPool(v.device, &dpci, nullptr, &pool),
                       "creating a descriptor pool");
      !s)
    return s.error();
  b.descriptor_pool_ = reinterpret_cast<std::uint64_t>(pool);
  if (info_.timestamp_period_ns > 0) {
    VkQueryPoolCreateInfo qpci{};
    qpci.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO;
    qpci.queryType = VK_QUERY_TYPE_TIMESTAMP;
    qpci.queryCount = max_passes + 1;
    VkQueryPool qp = VK_NULL_HANDLE;
    if (Status s =
            check(v.vkCreateQueryPool(v.device, &qpci, nullptr, &qp), "creating a timestamp pool");
        !s)
      return s.error();
    b.query_pool_ = reinterpret_cast<std::uint64_t>(qp);
    b.queries_ = max_passes + 1;
  }
  VkCommandBufferBeginInfo cbbi{};
  cbbi.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
  cbbi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  if (Status s = check(v.vkBeginCommandBuffer(cb, &cbbi), "recording commands"); !s)
    return s.error();
  if (b.query_pool_)
    v.vkCmdResetQueryPool(cb, reinterpret_cast<VkQueryPool>(b.query_pool_), 0, b.queries_);
  b.recording_ = true;
  return b;
}

Batch::Batch(Batch&& o) noexcept
    : context_(o.context_),
      command_buffer_(o.command_buffer_),
      query_pool_(o.query_pool_),
      descriptor_pool_(o.descriptor_pool_),
      passes_(std::move(o.passes_)),
      queries_(o.queries_),
      recording_(o.recording_),
      error_(std::move(o.error_)) {
  o.command_buffer_ = o.query_pool_ = o.descriptor_pool_ = 0;
  o.recording_ = false;
}

Batch::~Batch() {
  const Context::Impl& v = context_->impl();
  if (command_buffer_) {
    VkCommandBuffer cb = reinterpret_cast<VkCommandBuffer>(command_buffer_);
    v.vkFreeCommandBuffers(v.device, v.command_pool, 1, &cb);
  }
  if (descriptor_pool_)
    v.vkDestroyDescriptorPool(v.device, reinterpret_cast<VkDescriptorPool>(descriptor_pool_),
                              nullptr);
  if (query_pool_)
    v.vkDestroyQueryPool(v.device, reinterpret_cast<VkQueryPool>(query_pool_), nullptr);
}

void Batch::mark(const std::string& pass) {
  if (!recording_ || !query_pool_ || passes_.size() + 1 >= queries_) {
    passes_.push_back(pass);
    return;
  }
  const Context::Impl& v = context_->impl();
  v.vkCmdWriteTimestamp(reinterpret_cast<VkCommandBuffer>(command_buffer_),
                        VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT,
                        reinterpret_cast<VkQueryPool>(query_pool_), std::uint32_t(passes_.size()));
  passes_.push_back(pass);
}

void Batch::dispatch(const Kernel& k, std::span<Buffer* const> buffers, const void* push,
                     std::uint32_t groups_x, std::uint32_t groups_y, std::uint32_t groups_z) {
  Range ranges[kMaxBindings];
  const std::size_t n = std::min<std::size_t>(buffers.size(), kMaxBindings + 1);
  if (n > kMaxBindings) {
    error_ = Error{"Vulkan: kernel " + k.name_ + " given more than " +
                   std::to_string(kMaxBindings) + " buffers"};
    return;
  }
  for (std::size_t i = 0; i < n; ++i) ranges[i].buffer = buffers[i];
  dispatch(k, std::span<const Range>(ranges, n), push, groups_x, groups_y, groups_z);
}

void Batch::dispatch(const Kernel& k, std::span<const Range> buffers, const void* push,
                     std::uint32_t groups_x, std::uint32_t groups_y, std::uint32_t groups_z) {
  if (!recording_ || !error_) return;
  if (int(buffers.size()) != k.buffers_ || buffers.size() > kMaxBindings) {
    error_ = Error{"Vulkan: kernel " + k.name_ + " takes " + std::to_string(k.buffers_) +
                   " buffers, given " + std::to_string(buffers.size())};
    return;
  }
  const DeviceInfo& info = context_->info();
  for (const Range& r : buffers) {
    const std::size_t size = r.buffer ? r.buffer->bytes_ : 0;
    const std::size_t bytes = r.bytes ? r.bytes : size - std::min(r.offset, size);
    if (!r.buffer || r.offset >= size || bytes > size - r.offset ||
        r.offset % info.offset_alignment != 0 || bytes > info.max_buffer_bytes) {
      error_ =
          Error{"Vulkan: kernel " + k.name_ + " given a buffer range of " + std::to_string(bytes) +
                " bytes at " + std::to_string(r.offset) + " that it cannot bind"};
      return;
    }
  }
  const Context::Impl& v = context_->impl();
  VkCommandBuffer cb = reinterpret_cast<VkCommandBuffer>(command_buffer_);
  VkDescriptorSetLayout layout = reinterpret_cast<VkDescriptorSetLayout>(k.set_layout_);
  VkDescriptorSetAllocateInfo dsai{};
  dsai.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO;
  dsai.descriptorPool = reinterpret_cast<VkDescriptorPool>(descriptor_pool_);
  dsai.descriptorSetCount = 1;
  dsai.pSetLayouts = &layout;
  VkDescriptorSet set = VK_NULL_HANDLE;
  if (Status s = check(v.vkAllocateDescriptorSets(v.device, &dsai, &set),
                       "allocating a descriptor set (too many dispatches in one batch?)");
      !s) {
    error_ = s;
    return;
  }
  VkDescriptorBufferInfo infos[kMaxBindings];
  VkWriteDescriptorSet writes[kMaxBindings];
  for (std::size_t i = 0; i < buffers.size(); ++i) {
    infos[i] = {reinterpret_cast<VkBuffer>(buffers[i].buffer->buffer_), buffers[i].offset,
                buffers[i].bytes ? buffers[i].bytes : VK_WHOLE_SIZE};
    writes[i] = {};
    writes[i].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
    writes[i].dstSet = set;
    writes[i].dstBinding = std::uint32_t(i);
    writes[i].descriptorCount = 1;
    writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[i].pBufferInfo = &infos[i];
  }
  v.vkUpdateDescriptorSets(v.device, std::uint32_t(buffers.size()), writes, 0, nullptr);
  v.vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_COMPUTE,
                      reinterpret_cast<VkPipeline>(k.pipeline_));
  v.vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_COMPUTE,
                            reinterpret_cast<VkPipelineLayout>(k.layout_), 0, 1, &set, 0, nullptr);
  if (k.push_bytes_ > 0)
    v.vkCmdPushConstants(cb, reinterpret_cast<VkPipelineLayout>(k.layout_),
                         VK_SHADER_STAGE_COMPUTE_BIT, 0, k.push_bytes_, push);
  if (groups_x > 0 && groups_y > 0 && groups_z > 0)
    v.vkCmdDispatch(cb, groups_x, groups_y, groups_z);
  barrier(VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);
}

void Batch::barrier(std::uint32_t src_stage, std::uint32_t src_access) {
  // Whatever comes next (a dispatch or a copy) sees what this command wrote.
  const Context::Impl& v = context_->impl();
  VkMemoryBarrier b{};
  b.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER;
  b.srcAccessMask = src_access;
  b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT |
                    VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  v.vkCmdPipelineBarrier(reinterpret_cast<VkCommandBuffer>(command_buffer_), src_stage,
                         VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT, 0,
                         1, &b, 0, nullptr, 0, nullptr);
}

void Batch::copy(const Buffer& src, std::size_t src_offset, const Buffer& dst,
                 std::size_t dst_offset, std::size_t bytes) {
  if (!recording_ || !error_ || bytes == 0) return;
  if (src.context_ != context_ || dst.context_ != context_ || src_offset > src.bytes_ ||
      bytes > src.bytes_ - src_offset || dst_offset > dst.bytes_ ||
      bytes > dst.bytes_ - dst_offset) {
    error_ = Error{"Vulkan: a copy of " + std::to_string(bytes) + " bytes outside its buffers"};
    return;
  }
  const Context::Impl& v = context_->impl();
  VkBufferCopy region{src_offset, dst_offset, bytes};
  v.vkCmdCopyBuffer(reinterpret_cast<VkCommandBuffer>(command_buffer_),
                    reinterpret_cast<VkBuffer>(src.buffer_),
                    reinterpret_cast<VkBuffer>(dst.buffer_), 1, &region);
  barrier(VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
}

Expected<std::vector<std::pair<std::string, double>>> Batch::run() {
  if (!recording_) return Error{"Vulkan: the batch was already run"};
  recording_ = false;
  if (!error_) return error_.error();
  const Context::Impl& v = context_->impl();
  VkCommandBuffer cb = reinterpret_cast<VkCommandBuffer>(command_buffer_);
  const bool timed = query_pool_ && !passes_.empty() && passes_.size() < queries_;
  if (timed)
    v.vkCmdWriteTimestamp(cb, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT,
                          reinterpret_cast<VkQueryPool>(query_pool_),
                          std::uint32_t(passes_.size()));
  // What the kernels wrote is visible to the host after the fence.
  VkMemoryBarrier barrier{};
  barrier.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER;
  barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  v.vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                         VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0, nullptr, 0, nullptr);
  if (Status s = check(v.vkEndCommandBuffer(cb), "recording commands"); !s) return s.error();
  VkFenceCreateInfo fci{};
  fci.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
  VkFence fence = VK_NULL_HANDLE;
  if (Status s = check(v.vkCreateFence(v.device, &fci, nullptr, &fence), "creating a fence"); !s)
    return s.error();
  VkSubmitInfo si{};
  si.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cb;
  Status s = check(v.vkQueueSubmit(v.queue, 1, &si, fence), "submitting work");
  if (s) s = check(v.vkWaitForFences(v.device, 1, &fence, VK_TRUE, UINT64_MAX), "waiting");
  v.vkDestroyFence(v.device, fence, nullptr);
  if (!s) return s.error();
  std::vector<std::pair<std::string, double>> times;
  if (timed) {
    std::vector<std::uint64_t> ticks(passes_.size() + 1);
    if (Status q = check(
            v.vkGetQueryPoolResults(
                v.device, reinterpret_cast<VkQueryPool>(query_pool_), 0,
                std::uint32_t(ticks.size()), ticks.size() * sizeof(std::uint64_t), ticks.data(),
                sizeof(std::uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
            "reading timestamps");
        !q)
      return q.error();
    const double ns = context_->info().timestamp_period_ns;
    const std::uint32_t bits = context_->impl().timestamp_bits;
    const std::uint64_t mask = bits >= 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << bits) - 1;
    for (std::size_t i = 0; i < passes_.size(); ++i)  // counters wrap at their valid bits
      times.push_back({passes_[i], double((ticks[i + 1] - ticks[i]) & mask) * ns * 1e-6});
  }
  return times;
}

Groups groups_1d(std::size_t n, std::uint32_t size, const DeviceInfo& info) {
  const std::uint64_t groups = (n + size - 1) / size;
  const std::uint64_t max_x = std::max<std::uint32_t>(info.max_workgroups_x, 1);
  Groups g;
  g.x = std::uint32_t(std::min<std::uint64_t>(std::max<std::uint64_t>(groups, 1), max_x));
  g.y = std::uint32_t((groups + g.x - 1) / g.x);
  return g;
}

}  // namespace penumbra::gpu
