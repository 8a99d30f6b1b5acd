#pragma once
// Non-cryptographic 64-bit hashing for cache keys and determinism checks (leaf-root cache key,
// generated-scene hashes). Stable across runs and machines of the same endianness.
#include <cstdint>
#include <cstring>

namespace canopy {

inline uint64_t mix64(uint64_t h) {
  h ^= h >> 33;
  h *= 0xff51afd7ed558ccdull;
  h ^= h >> 33;
  h *= 0xc4ceb9fe1a85ec53ull;
  h ^= h >> 33;
  return h;
}

// Word-wise hash of a byte range (order-dependent), fast enough for gigabytes.
inline uint64_t hashBytes(uint64_t h, const void* data, size_t bytes) {
  const uint8_t* p = static_cast<const uint8_t*>(data);
  size_t i = 0;
  for (; i + 8 <= bytes; i += 8) {
    uint64_t w;
    std::memcpy(&w, p + i, 8);
    h = (h ^ w) * 0x100000001b3ull + (h >> 29);
  }
  uint64_t tail = 0;
  if (bytes > i) std::memcpy(&tail, p + i, bytes - i);
  h = (h ^ tail ^ bytes) * 0x100000001b3ull;
  return mix64(h);
}

}  // namespace canopy
