#pragma once
// Bearer tokens -> users (service.md "Sharing a queue"). The token file has one entry per line:
//   <token> <user> [admin]
// with '#' comments and blank lines allowed. Tokens are at least 16 characters of printable
// ASCII without spaces; users are [A-Za-z0-9._-]{1,64}. A malformed file is refused whole, naming
// the line, so a typo never silently locks a user out or lets one in. A file that group or others
// may read or write (any of mode 077) is refused, naming its mode and `chmod 600`, as ssh refuses
// a private key: whoever reads it can act as any user in it.
#include <map>
#include <optional>
#include <stdexcept>
#include <string>

namespace mdem::server {

struct TokenFileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Identity {
  std::string user;
  bool admin = false;
};

class TokenTable {
 public:
  static TokenTable load(const std::string& path);  // throws TokenFileError
  std::optional<Identity> find(const std::string& token) const;
  std::size_t size() const { return by_token_.size(); }

 private:
  std::map<std::string, Identity> by_token_;
};

}  // namespace mdem::server
