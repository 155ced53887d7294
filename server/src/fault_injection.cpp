#include "fault_injection.h"

#include <sys/stat.h>

#include <cstdlib>

namespace mdem::server {

std::optional<std::string> injected_write_failure() {
  static const char* const path = std::getenv("MDEMD_FAULT_FILE");
  if (path == nullptr || *path == '\0') return std::nullopt;
  struct stat st {};
  if (::stat(path, &st) != 0) return std::nullopt;
  return std::string("No space left on device (injected: MDEMD_FAULT_FILE '") + path + "' exists)";
}

}  // namespace mdem::server
