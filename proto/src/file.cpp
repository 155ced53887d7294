// load_file: a spec file, chosen by extension, read with a size limit.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>

#include "input.h"
#include "mdem/spec.h"

namespace mdem::spec {

namespace {

namespace fs = std::filesystem;

enum class Format { Json, Yaml };

constexpr const char* kAllowedExtensions = "(allowed: .json, .yaml, .yml)";

[[noreturn]] void fail(const std::string& message) { throw SpecError({{"file", message}}); }

std::string in_quotes(const std::string& path) { return "\"" + path + "\""; }

Format format_of(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".json") return Format::Json;
  if (ext == ".yaml" || ext == ".yml") return Format::Yaml;
  if (ext.empty()) fail(in_quotes(path) + " has no extension " + kAllowedExtensions);
  fail(in_quotes(path) + " has the extension " + in_quotes(ext) + " " + kAllowedExtensions);
}

// A regular file no larger than kMaxSpecBytes.
void check_file(const std::string& path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (st.type() == fs::file_type::not_found) fail(in_quotes(path) + ": no such file");
  if (ec) fail(in_quotes(path) + ": " + ec.message());  // e.g. permission denied on a directory
  if (fs::is_directory(st)) fail(in_quotes(path) + " is a directory, not a spec file");
  if (!fs::is_regular_file(st)) fail(in_quotes(path) + " is not a regular file");
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) fail(in_quotes(path) + ": " + ec.message());
  detail::check_size(size, "file", in_quotes(path));
}

// Reads in chunks and stops past kMaxSpecBytes, so a file that grew after the check is refused.
std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(in_quotes(path) + " cannot be opened for reading");
  std::string text;
  char chunk[1 << 16];
  while (in.read(chunk, sizeof chunk) || in.gcount() > 0) {
    text.append(chunk, static_cast<std::size_t>(in.gcount()));
    detail::check_size(text.size(), "file", in_quotes(path));
  }
  if (in.bad()) fail(in_quotes(path) + " could not be read");
  return text;
}

}  // namespace

mdem::v1::JobSpec load_file(const std::string& path) {
  const Format format = format_of(path);
  check_file(path);
  const std::string text = read_text(path);
  return format == Format::Json ? parse_json(text) : parse_yaml(text);
}

}  // namespace mdem::spec
