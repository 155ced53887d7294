#include "run_log.h"

#include <cerrno>
#include <cstring>
#include <system_error>

#include "flags.h"

namespace mdem::cli {

namespace fs = std::filesystem;

int TeeBuf::overflow(int c) {
  if (c == traits_type::eof()) return traits_type::not_eof(c);
  const auto ch = traits_type::to_char_type(c);
  if (a_->sputc(ch) == traits_type::eof()) return traits_type::eof();
  if (b_) b_->sputc(ch);
  return c;
}

std::streamsize TeeBuf::xsputn(const char* s, std::streamsize n) {
  const std::streamsize w = a_->sputn(s, n);
  if (b_) b_->sputn(s, n);
  return w;
}

int TeeBuf::sync() {
  const int r = a_->pubsync();
  if (b_) b_->pubsync();
  return r;
}

fs::path default_log_path(const std::string& db, const std::string& id) {
  const fs::path dir = fs::path(db).parent_path();
  return (dir.empty() ? fs::path(".") : dir) / "logs" / (id + ".log");
}

namespace {

void open_log(std::ofstream& f, const fs::path& path, bool append) {
  std::error_code ec;
  if (path.has_parent_path()) fs::create_directories(path.parent_path(), ec);
  if (ec)
    throw UsageError("--log " + path.string() + ": cannot create its directory (" + ec.message() +
                     "); give a writable path, or --no-log");
  if (fs::is_directory(path, ec))
    throw UsageError("--log " + path.string() + ": is a directory; give a file path, or --no-log");
  errno = 0;
  f.open(path, std::ios::out | (append ? std::ios::app : std::ios::trunc));
  if (!f)
    throw UsageError("--log " + path.string() + ": cannot be written (" +
                     (errno ? std::strerror(errno) : "open failed") +
                     "); give a writable path, or --no-log");
}

}  // namespace

RunLog::RunLog(std::ostream& out, std::ostream& err)
    : out_buf_(out.rdbuf(), &held_),
      err_buf_(err.rdbuf(), &held_),
      out_(&out_buf_),
      err_(&err_buf_) {
  // Standard error shows what standard output holds first, as std::cerr (tied to std::cout)
  // does.
  err_.tie(&out_);
}

void RunLog::open(const fs::path& path, bool append) {
  out_.flush();
  err_.flush();
  open_log(file_, path, append);
  path_ = path;
  file_ << held_.str();
  held_.str("");
  out_buf_.set_second(file_.rdbuf());
  err_buf_.set_second(file_.rdbuf());
}

RunLog::~RunLog() {
  out_.flush();
  err_.flush();
}

void RunLog::discard() {
  out_buf_.set_second(nullptr);
  err_buf_.set_second(nullptr);
  if (!file_.is_open()) return;
  file_.close();
  std::error_code ec;
  fs::remove(path_, ec);
}

}  // namespace mdem::cli
