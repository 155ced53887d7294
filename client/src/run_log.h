#pragma once
// The log file of a local run (`mdem run --log PATH`, on by default beside the results database:
// <db dir>/logs/<job id>.log): a copy of what the terminal showed, without the progress bar's
// redraws. The run writes its text to two tee streams (standard output and error each copied
// into the log, in the order written); the bar goes to the terminal only.
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <ostream>
#include <sstream>
#include <streambuf>
#include <string>

namespace mdem::cli {

// A stream buffer writing everything to `a` and, when given, to `b`.
class TeeBuf : public std::streambuf {
 public:
  TeeBuf(std::streambuf* a, std::streambuf* b) : a_(a), b_(b) {}
  void set_second(std::streambuf* b) { b_ = b; }

 protected:
  int overflow(int c) override;
  std::streamsize xsputn(const char* s, std::streamsize n) override;
  int sync() override;

 private:
  std::streambuf *a_, *b_;
};

// The default log path of job `id` with results in database `db`: <db dir>/logs/<id>.log.
std::filesystem::path default_log_path(const std::string& db, const std::string& id);

// The log of one run: `out` and `err` are the terminal's streams, copied into memory until
// open() names the file, which then receives what was held and everything after. A path that
// cannot be written throws UsageError naming it and what to do (the caller opens the log before
// the job exists, so nothing of it is lost). Without open() nothing is written anywhere.
class RunLog {
 public:
  RunLog(std::ostream& out, std::ostream& err);
  ~RunLog();
  RunLog(const RunLog&) = delete;
  RunLog& operator=(const RunLog&) = delete;
  // append: after what the file holds (a resumed job's log), else in its place.
  void open(const std::filesystem::path& path, bool append = false);
  std::ostream& out() { return out_; }
  std::ostream& err() { return err_; }
  const std::filesystem::path& path() const { return path_; }
  bool enabled() const { return file_.is_open(); }
  // Closes and deletes the file (a job that never started: nothing to keep).
  void discard();

 private:
  std::filesystem::path path_;
  std::stringbuf held_;
  std::ofstream file_;
  TeeBuf out_buf_, err_buf_;
  std::ostream out_, err_;
};

}  // namespace mdem::cli
