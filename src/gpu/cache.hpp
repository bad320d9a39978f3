// What the GPU backend keeps between renders: compiled kernels, working buffers by role, and
// small tables already on the device (uploaded again only when their bytes change). Each buffer
// has an owner (the scene, a method, one of its options): a render keeps the buffers of the
// owners it uses and frees the others.
#pragma once

#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "gpu/vulkan.hpp"

namespace penumbra::gpu {

// Who a buffer belongs to: a small number the client names (a world's solver keeps an enum).
using Owner = std::uint32_t;

class Cache {
 public:
  explicit Cache(const Context& context) : context_(context) {}
  const Context& context() const { return context_; }

  Expected<const Kernel*> kernel(const std::string& name, std::span<const std::uint32_t> spirv,
                                 int buffers, std::uint32_t push_bytes);
  // The buffer kept under `role` for `owner`, allocated again only when its size or memory
  // changes. One role has one size within a batch (a reallocation frees what recorded commands
  // refer to). Roles are unique across owners.
  Expected<Buffer*> buffer(Owner owner, const std::string& role, std::size_t bytes,
                           Memory where = Memory::device, bool in_pieces = false);
  // A device buffer under `role` holding `bytes` of `data`, copied in `batch` through a staging
  // buffer unless it holds these bytes already. Counts into uploaded.
  Expected<Buffer*> table(Batch& batch, Owner owner, const std::string& role, const void* data,
                          std::size_t bytes);

  // After a batch that failed or was never run: no table is trusted to be on the device.
  void forget_tables() {
    for (auto& [role, held] : buffers_) held.table.clear();
  }
  // Frees every buffer whose owner is not in `keep` (a render with other options keeps only what
  // it shares with the last one, so memory checks see what is really allocated); with nothing
  // listed, every buffer.
  void release_except(std::span<const Owner> keep);

  // Bytes of the buffers held in `where`.
  std::uint64_t allocated(Memory where) const;

  std::uint64_t uploaded = 0;  // bytes copied to the GPU since the caller last reset it

 private:
  const Context& context_;
  std::map<std::string, Kernel> kernels_;
  struct Held {
    Buffer buffer;
    Owner owner;
    Memory where;
    std::vector<unsigned char> table;  // for a table: the bytes the device holds
  };
  std::map<std::string, Held> buffers_;  // node-based: pointers stay valid as roles are added
};

}  // namespace penumbra::gpu
