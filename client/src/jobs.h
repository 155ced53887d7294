#pragma once
// The job kinds `mdem run` knows, each in its own file.
#include <ostream>
#include <string>
#include <vector>

namespace mdem::cli {

int run_twist(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace mdem::cli
