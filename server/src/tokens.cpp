#include "tokens.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <regex>
#include <sstream>

namespace mdem::server {
namespace {

// The token file's text, read from the file whose mode was checked (fstat of the open file, so
// the check and the read see the same file).
std::string read_private_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    throw TokenFileError("token file '" + path + "': cannot open (missing or unreadable)");
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw TokenFileError("token file '" + path + "': not a regular file");
  }
  if ((st.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    ::close(fd);
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    throw TokenFileError("token file '" + path + "' has mode " + mode +
                         ": group or others may read or change it, and anyone who reads it can "
                         "act as every user it lists. Make it private with `chmod 600 " +
                         path +
                         "` (the daemon refuses it otherwise, as ssh refuses a private key)");
  }
  std::string text;
  char buf[4096];
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;)
    text.append(buf, static_cast<std::size_t>(n));
  ::close(fd);
  return text;
}

}  // namespace

TokenTable TokenTable::load(const std::string& path) {
  std::istringstream in(read_private_file(path));
  static const std::regex user_re("[A-Za-z0-9._-]{1,64}");
  TokenTable t;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    std::istringstream ss(line);
    std::string token, user, flag, extra;
    if (!(ss >> token)) continue;
    auto bad = [&](const std::string& why) {
      throw TokenFileError("token file '" + path + "' line " + std::to_string(n) + ": " + why +
                           " (expected: <token> <user> [admin])");
    };
    if (!(ss >> user)) bad("no user after the token");
    if (ss >> flag && flag != "admin") bad("'" + flag + "' is not allowed here (only 'admin')");
    if (ss >> extra) bad("too many fields");
    if (token.size() < 16) bad("token shorter than 16 characters");
    for (unsigned char c : token)
      if (c < 0x21 || c > 0x7e) bad("token holds a character outside printable ASCII");
    if (!std::regex_match(user, user_re)) bad("user '" + user + "' is not [A-Za-z0-9._-]{1,64}");
    if (t.by_token_.count(token)) bad("token listed twice");
    t.by_token_[token] = {user, flag == "admin"};
  }
  if (t.by_token_.empty())
    throw TokenFileError("token file '" + path + "': no tokens (nobody could use the daemon)");
  return t;
}

std::optional<Identity> TokenTable::find(const std::string& token) const {
  auto it = by_token_.find(token);
  if (it == by_token_.end()) return std::nullopt;
  return it->second;
}

}  // namespace mdem::server
