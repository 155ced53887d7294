#include "mdem/job_id.h"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <mutex>
#include <random>
#include <stdexcept>

namespace mdem {

std::string new_job_id(int random_hex) {
  if (random_hex < 1 || random_hex > 16)
    throw std::invalid_argument("new_job_id: random_hex must be in [1, 16], got " +
                                std::to_string(random_hex));
  static std::mutex mu;
  static std::mt19937_64 rng{std::random_device{}()};
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "j-%Y%m%d-%H%M%S-", &tm);
  unsigned long long bits;
  {
    std::lock_guard lock(mu);
    bits = rng();
  }
  if (random_hex < 16) bits &= (1ULL << (4 * random_hex)) - 1;
  char tail[24];
  std::snprintf(tail, sizeof tail, "%0*llx", random_hex, bits);
  return std::string(stamp) + tail;
}

}  // namespace mdem
