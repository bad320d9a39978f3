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

Expected<Buffer*> Cache::buffer(const std::string& role, std::size_t bytes, Memory where,
                                bool in_pieces) {
  bytes = std::max<std::size_t>(bytes, 4);
  auto it = buffers_.find(role);
  if (it != buffers_.end() && it->second.bytes() == bytes && memory_[role] == where)
    return &it->second;
  if (it != buffers_.end()) {
    buffers_.erase(it);  // freed before the new one is allocated: the two need not fit at once
    tables_.erase(role);
  }
  Expected<Buffer> b = context_.buffer(bytes, where, in_pieces);
  if (!b) return b.error();
  memory_[role] = where;
  return &buffers_.emplace(role, std::move(*b)).first->second;
}

Expected<Buffer*> Cache::table(Batch& batch, const std::string& role, const void* data,
                               std::size_t bytes) {
  Expected<Buffer*> device = buffer(role, bytes);
  if (!device) return device.error();
  std::vector<unsigned char>& held = tables_[role];
  if (held.size() == bytes && std::memcmp(held.data(), data, bytes) == 0) return *device;
  Expected<Buffer*> staging = buffer(role + " staging", bytes, Memory::host);
  if (!staging) return staging.error();
  std::memcpy((*staging)->data(), data, bytes);
  batch.copy(**staging, 0, **device, 0, bytes);
  held.assign(static_cast<const unsigned char*>(data),
              static_cast<const unsigned char*>(data) + bytes);
  uploaded += bytes;
  return *device;
}

void Cache::release(const std::string& role) {
  buffers_.erase(role);
  memory_.erase(role);
  tables_.erase(role);
}

std::uint64_t Cache::allocated(Memory where) const {
  std::uint64_t bytes = 0;
  for (const auto& [role, buffer] : buffers_)
    if (memory_.at(role) == where) bytes += buffer.bytes();
  return bytes;
}

void Cache::release_except(std::span<const std::string> keep) {
  for (auto it = buffers_.begin(); it != buffers_.end();) {
    if (std::any_of(keep.begin(), keep.end(),
                    [&](const std::string& k) { return it->first.starts_with(k); })) {
      ++it;
      continue;
    }
    tables_.erase(it->first);
    memory_.erase(it->first);
    it = buffers_.erase(it);
  }
}

}  // namespace penumbra::gpu
