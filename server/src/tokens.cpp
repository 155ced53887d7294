#include "tokens.h"

#include <fstream>
#include <regex>
#include <sstream>

namespace mdem::server {

TokenTable TokenTable::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw TokenFileError("token file '" + path + "': cannot open (missing or unreadable)");
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
