// A small Vulkan layer for compute: instance and device, buffers, compute kernels, command
// submission and timestamp queries. Only what the GPU backend needs. The loader (libvulkan.so.1)
// is opened at run time, so a machine without Vulkan gets an error message, not a program that
// cannot start. Every VkResult is checked and becomes an Error naming the call that failed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "penumbra/error.hpp"

namespace penumbra::gpu {

struct DeviceInfo {
  std::string name;
  std::string type;  // "discrete", "integrated", "virtual", "cpu" or "other"
  bool cpu = false;  // a CPU driver such as lavapipe
  std::uint64_t device_local_bytes = 0;
  double timestamp_period_ns = 0;  // 0: the queue has no timestamps
  std::uint32_t max_workgroups_x = 0, max_workgroups_y = 0;
  std::uint64_t max_buffer_bytes = 0;  // the largest storage buffer range a kernel can bind
  std::uint64_t offset_alignment =
      1;                     // of a bound range's offset (minStorageBufferOffsetAlignment)
  bool storage_f16 = false;  // 16-bit floats in storage buffers (storageBuffer16BitAccess)
};

// Workgroups for n invocations of a 1-D kernel with `size` per group, folded into x and y so
// that neither passes the device's limit: the kernel's index is
// gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * size.
struct Groups {
  std::uint32_t x = 1, y = 1;
};
Groups groups_1d(std::size_t n, std::uint32_t size, const DeviceInfo& info);

class Context;

// Where a buffer lives: host-visible memory, mapped, for what the host writes or reads back; or
// device-local memory for what only kernels touch (filled and read through Batch::copy).
enum class Memory { host, device };

// A storage buffer.
class Buffer {
 public:
  Buffer() = default;
  ~Buffer();
  Buffer(Buffer&& other) noexcept;
  Buffer& operator=(Buffer&& other) noexcept;
  std::size_t bytes() const { return bytes_; }
  void* data() const { return mapped_; }  // Memory::host: persistently mapped, coherent; else null
  template <class T>
  T* as() const {
    return static_cast<T*>(mapped_);
  }

 private:
  friend class Context;
  friend class Batch;
  void release();
  const Context* context_ = nullptr;
  std::uint64_t buffer_ = 0, memory_ = 0;  // VkBuffer, VkDeviceMemory
  std::size_t bytes_ = 0;
  void* mapped_ = nullptr;
};

// A compute pipeline: one SPIR-V module whose bindings 0..buffers-1 are storage buffers, with a
// push-constant block of `push_bytes`.
class Kernel {
 public:
  Kernel() = default;
  ~Kernel();
  Kernel(Kernel&& other) noexcept;
  Kernel& operator=(Kernel&& other) noexcept;
  const std::string& name() const { return name_; }

 private:
  friend class Context;
  friend class Batch;
  void release();
  const Context* context_ = nullptr;
  std::string name_;
  int buffers_ = 0;
  std::uint32_t push_bytes_ = 0;
  std::uint64_t module_ = 0, set_layout_ = 0, layout_ = 0, pipeline_ = 0;
};

// Dispatches recorded into one command buffer, each followed by a barrier so that the next reads
// what it wrote, then submitted and waited for. With timestamps, each named pass is timed.
class Batch {
 public:
  ~Batch();
  Batch(Batch&&) noexcept;
  Batch& operator=(Batch&&) = delete;
  Batch(const Batch&) = delete;

  // `groups` workgroups in x, y and z. Buffers are bound in order to bindings 0, 1, ...
  void dispatch(const Kernel& kernel, std::span<Buffer* const> buffers, const void* push,
                std::uint32_t groups_x, std::uint32_t groups_y = 1, std::uint32_t groups_z = 1);
  // The same with part of a buffer at a binding: `bytes` from `offset` (a multiple of
  // DeviceInfo::offset_alignment; 0 bytes: to the end), for buffers larger than one binding.
  struct Range {
    const Buffer* buffer = nullptr;
    std::size_t offset = 0, bytes = 0;
  };
  void dispatch(const Kernel& kernel, std::span<const Range> ranges, const void* push,
                std::uint32_t groups_x, std::uint32_t groups_y = 1, std::uint32_t groups_z = 1);
  // Copies bytes between buffers (host to device for uploads, device to host to read back).
  void copy(const Buffer& src, std::size_t src_offset, const Buffer& dst, std::size_t dst_offset,
            std::size_t bytes);
  // Starts a timed pass (ends at the next mark or at submit).
  void mark(const std::string& pass);
  // Submits and waits. Pass times in milliseconds, in the order of mark().
  Expected<std::vector<std::pair<std::string, double>>> run();

 private:
  friend class Context;
  explicit Batch(const Context* c) : context_(c) {}
  void barrier(std::uint32_t src_stage, std::uint32_t src_access);
  const Context* context_;
  std::uint64_t command_buffer_ = 0, query_pool_ = 0, descriptor_pool_ = 0;
  std::vector<std::string> passes_;
  std::uint32_t queries_ = 0;
  bool recording_ = false;
  Status error_;
};

// Buffers, kernels and batches refer to their Context, which must outlive them. A Context is
// used by one thread at a time (its command pool and queue are not locked).
class Context {
 public:
  // Opens the Vulkan loader and the first suitable device: a hardware GPU when there is one;
  // with allow_cpu, a CPU driver (lavapipe) otherwise.
  static Expected<std::shared_ptr<Context>> create(bool allow_cpu);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  const DeviceInfo& info() const { return info_; }
  // A buffer larger than max_buffer_bytes is refused unless `in_pieces`: then the caller binds
  // it only in ranges (Batch::Range) of at most that size.
  Expected<Buffer> buffer(std::size_t bytes, Memory where = Memory::host,
                          bool in_pieces = false) const;
  Expected<Kernel> kernel(const std::string& name, std::span<const std::uint32_t> spirv,
                          int buffers, std::uint32_t push_bytes) const;
  Expected<Batch> batch(std::uint32_t max_passes = 32) const;

  struct Impl;
  const Impl& impl() const { return *impl_; }

 private:
  Context() = default;
  std::unique_ptr<Impl> impl_;
  DeviceInfo info_;
};

}  // namespace penumbra::gpu
