#pragma once
// `mdem ls` and `mdem show` on a daemon: results_commands.cpp hands over to these when --server
// or $MDEM_SERVER names one. `given`: the parsed flags (the connection flags among them).
#include <map>
#include <ostream>
#include <string>

#include "mdem/job_state.h"
#include "remote.h"
#include "results_store.h"

namespace mdem::cli {

// The local record of a daemon's job, from what the daemon says of it. The state starts at
// QUEUED unless given: the events bring it up to date as they are stored.
JobRecord record_of(const v1::JobInfo& info, const ConnectionSettings& settings,
                    const std::string& state = job_state_name(v1::QUEUED));

int remote_ls(const std::map<std::string, std::string>& given, std::ostream& out,
              std::ostream& err);
int remote_show(const std::string& id, const std::map<std::string, std::string>& given,
                std::ostream& out, std::ostream& err);

}  // namespace mdem::cli
