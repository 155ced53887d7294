#pragma once
// Bytes a container holds on the heap (its capacity, not its size): what the memory accounting
// of the engine's data (System::memory_bytes) adds up.
#include <cstddef>
#include <vector>

namespace mdem {

template <class T>
std::size_t capacity_bytes(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}

// Of a vector of vectors: the outer array and every inner one.
template <class T>
std::size_t capacity_bytes(const std::vector<std::vector<T>>& v) {
  std::size_t b = v.capacity() * sizeof(std::vector<T>);
  for (const std::vector<T>& inner : v) b += inner.capacity() * sizeof(T);
  return b;
}

}  // namespace mdem
