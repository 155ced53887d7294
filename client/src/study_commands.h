#pragma once
// The study parts of other commands: `mdem plot ID` and `mdem ls --study ID` of a study in the
// local results database (client/src/study.cpp).
#include <map>
#include <ostream>
#include <string>
#include <vector>

namespace mdem::cli {

// Draws the study's errors against wall time to out_path ("" = <study id>.png).
int plot_study(const std::string& id, const std::string& db, const std::string& out_path,
               std::ostream& out);
// `mdem watch --study ID` / `mdem cancel --study ID`: each job of a study on the daemon followed
// (then the study's table, as `mdem study show`) or cancelled. A study that is not in the local
// database is taken from the daemon that --server (or $MDEM_SERVER) names, by its full id.
// names_study: whether args hold
// --study.
bool names_study(const std::vector<std::string>& args);
int watch_study(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cancel_study(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
// The study's jobs: its varied values, job id, state, wall time (a JSON array with json).
int ls_study(const std::string& id, const std::string& db, bool json, std::ostream& out);
// `mdem ls --study ID --server HOST:PORT`: the study's jobs as the daemon lists them (any client
// of the same user: the daemon keeps the study id with each job). `given`: the parsed flags.
int ls_daemon_study(const std::string& id, const std::map<std::string, std::string>& given,
                    bool json, std::ostream& out, std::ostream& err);

}  // namespace mdem::cli
