#pragma once
// `mdem ls` and `mdem show` on a daemon: results_commands.cpp hands over to these when --server
// or $MDEM_SERVER names one. `given`: the parsed flags (the connection flags among them).
#include <map>
#include <ostream>
#include <string>

namespace mdem::cli {

int remote_ls(const std::map<std::string, std::string>& given, std::ostream& out,
              std::ostream& err);
int remote_show(const std::string& id, const std::map<std::string, std::string>& given,
                std::ostream& out, std::ostream& err);

}  // namespace mdem::cli
