#pragma once
// Helpers shared by the tests: temporary directories and files, the in-process CLI, and the
// system-level checks (static equilibrium).
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "mdem/cli.h"
#include "mdem/integrate/system.h"

namespace mdem::testing {

// A fresh directory under the system's temp directory (PREFIX-XXXXXX), removed with its contents
// at the end of the scope.
class TempDir {
 public:
  explicit TempDir(const std::string& prefix) {
    std::string tmpl = (std::filesystem::temp_directory_path() / (prefix + "-XXXXXX")).string();
    path_ = mkdtemp(tmpl.data());
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  // Writes TEXT to the file NAME in the directory; returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path_ / name) << text;
    return file(name);
  }

 private:
  std::filesystem::path path_;
};

// Directories that outlive one scope (a daemon's data directory that several steps of a test
// read, a database a whole test program shares): made fresh under the system's temp directory,
// removed when the test program ends with every test passed, kept and named on stderr when one
// failed, for the post-mortem. Before this, every ctest run left ~600 of them (1.7 GB) in /tmp.
class ScratchDirs : public ::testing::Environment {
 public:
  // temp/NAME, emptied and created.
  static std::filesystem::path make(const std::string& name) {
    const std::filesystem::path d = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(d);
    std::filesystem::create_directories(d);
    made().push_back(d);
    return d;
  }
  void TearDown() override {
    const bool passed = ::testing::UnitTest::GetInstance()->Passed();
    for (const auto& d : made()) {
      if (!passed) {
        std::fprintf(stderr, "a test failed: its directory %s is kept\n", d.c_str());
        continue;
      }
      std::error_code ec;
      std::filesystem::remove_all(d, ec);
    }
  }

 private:
  static std::vector<std::filesystem::path>& made() {
    static std::vector<std::filesystem::path> dirs;
    return dirs;
  }
};
inline ::testing::Environment* const kScratchDirsCleanup =
    ::testing::AddGlobalTestEnvironment(new ScratchDirs);

// The whole content of a file (empty when it cannot be read).
inline std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Seconds since t0 on the steady clock.
inline double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The user's mdem settings would change what the CLI does: none of them (for tests that run it).
inline void clear_mdem_env() {
  for (const char* v : {"MDEM_SERVER", "MDEM_TOKEN", "MDEM_CONFIG", "MDEM_DB"}) ::unsetenv(v);
}

// a followed by b (command lines built from parts).
inline std::vector<std::string> operator+(std::vector<std::string> a,
                                          const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

inline bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// What a CLI call gave: its exit code, standard output and standard error.
struct CliResult {
  int code = -1;
  std::string out, err;
};

// Runs a shell command: its exit code (-1 when a signal ended it) and standard output.
inline CliResult run_shell(const std::string& cmd) {
  FILE* pipe = ::popen(cmd.c_str(), "r");
  CliResult r;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof buf, pipe)) r.out.append(buf, n);
  const int status = ::pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// In-process `mdem run KIND ARGS`.
inline CliResult run_job(const std::string& kind, std::vector<std::string> args) {
  args.insert(args.begin(), kind);
  std::ostringstream out, err;
  const int code = cli::run(args, out, err);
  return {code, out.str(), err.str()};
}

// base plus more; a flag in `more` replaces the same flag (and its value) in base.
inline std::vector<std::string> with(std::vector<std::string> base,
                                     const std::vector<std::string>& more) {
  for (std::size_t k = 0; k < more.size(); ++k) {
    if (more[k].rfind("--", 0) != 0) continue;
    auto it = std::find(base.begin(), base.end(), more[k]);
    if (it != base.end()) base.erase(it, it + 2);
  }
  base.insert(base.end(), more.begin(), more.end());
  return base;
}

// Largest unbalanced force (eV/nm) and moment (eV) on free DOFs: internal + external.
inline double max_unbalanced(const System& sys) {
  const Elements& el = sys.elements();
  double m = 0;
  for (std::size_t i = 0; i < el.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      if (el.dof[i][k] == DofMode::Free) m = std::max(m, std::abs(el.f[i][k] + el.f_ext[i][k]));
      if (el.dof[i][k + 3] == DofMode::Free) m = std::max(m, std::abs(el.t[i][k] + el.t_ext[i][k]));
    }
  return m;
}

// Runs a damped system in chunks until the unbalanced force falls below tol and the kinetic
// energy below ke_tol (static equilibrium), or max_steps pass. Returns the steps taken.
inline long relax(System& sys, double tol, double ke_tol, long max_steps, long chunk = 2000) {
  long done = 0;
  while (done < max_steps) {
    sys.run(chunk);
    done += chunk;
    if (max_unbalanced(sys) < tol && sys.energy().kinetic() < ke_tol) break;
  }
  return done;
}

// The change of y over the span of t along the least-squares line through (t, y): an energy
// record's drift, free of its oscillation.
inline double linear_trend(const std::vector<double>& t, const std::vector<double>& y) {
  const double n = static_cast<double>(t.size());
  double st = 0, sy = 0, stt = 0, sty = 0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    st += t[k];
    sy += y[k];
    stt += t[k] * t[k];
    sty += t[k] * y[k];
  }
  const double slope = (n * sty - st * sy) / (n * stt - st * st);
  return slope * (t.back() - t.front());
}

}  // namespace mdem::testing
