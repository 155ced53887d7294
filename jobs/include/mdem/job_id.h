#pragma once
// Job ids, for `mdem run` (the local results database) and mdemd alike: "j-" + the UTC time of
// creation (YYYYMMDD-HHMMSS) + "-" + random hex digits, so ids sort by creation time and a
// prefix names a job.
#include <string>

namespace mdem {

// A new id with `random_hex` random hex digits (1..16): "j-20260102-030405-abcd". Thread-safe.
std::string new_job_id(int random_hex = 4);

}  // namespace mdem
