// A queued job's place in the queue and what it waits for.
#include "queue_place.h"

#include <algorithm>

namespace mdem::server {
namespace {

std::string named(const JobOwner& job, const Identity& who) {
  return who.admin || job.user == who.user ? job.id : "another user's job";
}

}  // namespace

void describe_wait(v1::JobInfo& info, const std::vector<JobOwner>& queue,
                   const std::vector<JobOwner>& running, int workers, const Identity& who) {
  if (info.state() != v1::QUEUED) return;
  const auto it = std::find_if(queue.begin(), queue.end(),
                               [&](const JobOwner& j) { return j.id == info.job_id(); });
  if (it == queue.end()) return;  // started or cancelled since
  const long position = it - queue.begin() + 1;
  info.set_queue_position(static_cast<int>(position));
  std::string text;
  if (static_cast<int>(running.size()) >= workers) {
    text = "all " + std::to_string(workers) + (workers == 1 ? " worker" : " workers") +
           " busy (running ";
    for (std::size_t k = 0; k < running.size(); ++k)
      text += (k ? ", " : "") + named(running[k], who);
    text += ")";
  } else {
    text = "a worker is free: starting";
  }
  if (position > 1)
    text += "; position " + std::to_string(position) + " in the queue, behind " +
            named(*(it - 1), who) +
            " (the user with the fewest running jobs goes first, then the oldest job)";
  else
    text += "; next to start";
  info.set_waiting_for(text);
}

}  // namespace mdem::server
