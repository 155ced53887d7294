#pragma once
// The peak resident set of this process (getrusage's ru_maxrss): what the daemon reports beside
// each job's own data peak, and `mdem run` in its end block. A thread has no RSS of its own, so
// in the daemon it is every job's (and the daemon's) at once.
namespace mdem {

// Bytes; 0 when the system cannot say.
long process_rss_peak_bytes();

}  // namespace mdem
