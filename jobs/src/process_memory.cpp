#include "mdem/process_memory.h"

#include <sys/resource.h>

namespace mdem {

long process_rss_peak_bytes() {
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) != 0) return 0;
  return static_cast<long>(u.ru_maxrss) * 1024L;  // Linux: kB
}

}  // namespace mdem
