#include "gpu/cache.hpp"

#include <algorithm>
#include <cstring>

namespace penumbra::gpu {

Expected<const Kernel*> Cache::kernel(const std::string& name, std::span<const std::uint32_t> spirv,
                                      int buffers, std::uint32_t push_bytes) {
  auto it = kernels_.find(name);
  if (it == kernels_.end()) {
    Expected<Kernel> k = context_.kernel(name, spirv, buffers, push_bytes);
    if (!k) return k.error();
    it = kernels_.emplace(name, std::move(*k)).first;
  }
  return &it->second;
}

Expected<Buffer*> Cache::buffer(Owner owner, const std::string& role, std::size_t bytes,
                                Memory where, bool in_pieces) {
  bytes = std::max<std::size_t>(bytes, 4);
  auto it = buffers_.find(role);
  if (it != buffers_.end() && it->second.buffer.bytes() == bytes && it->second.where == where) {
    it->second.owner = owner;
    return &it->second.buffer;
  }
  // The old buffer is freed before the new one is allocated: the two need not fit at once.
  if (it != buffers_.end()) buffers_.erase(it);
  Expected<Buffer> b = context_.buffer(bytes, where, in_pieces);
  if (!b) return b.error();
  return &buffers_.emplace(role, Held{std::move(*b), owner, where, {}}).first->second.buffer;
}

Expected<Buffer*> Cache::table(Batch& batch, Owner owner, const std::string& role, const void* data,
                               std::size_t bytes) {
  Expected<Buffer*> device = buffer(owner, role, bytes);
  if (!device) return device.error();
  std::vector<unsigned char>& held = buffers_.at(role).table;
  if (held.size() == bytes && std::memcmp(held.data(), data, bytes) == 0) return *device;
  Expected<Buffer*> staging = buffer(owner, role + " staging", bytes, Memory::host);
  if (!staging) return staging.error();
  std::memcpy((*staging)->data(), data, bytes);
  batch.copy(**staging, 0, **device, 0, bytes);
  held.assign(static_cast<const unsigned char*>(data),
              static_cast<const unsigned char*>(data) + bytes);
  uploaded += bytes;
  return *device;
}

std::uint64_t Cache::allocated(Memory where) const {
  std::uint64_t bytes = 0;
  for (const auto& [role, held] : buffers_)
    if (held.where == where) bytes += held.buffer.bytes();
  return bytes;
}

void Cache::release_except(std::span<const Owner> keep) {
  std::erase_if(buffers_, [&](const auto& entry) {
    return std::find(keep.begin(), keep.end(), entry.second.owner) == keep.end();
  });
}

}  // namespace penumbra::gpu
