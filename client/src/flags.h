#pragma once
// Command-line parsing shared by every `mdem` command: `--flag value` or `--flag=value`, finite
// numbers only, and errors that name the flag and what it allows.
#include <map>
#include <nlohmann/json.hpp>
#include <ostream>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace mdem::cli {

// A bad command line: the message names the flag and what is allowed (exit code kUsage).
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Flags of one command: names with a value, and switches without one.
struct FlagSpec {
  std::vector<std::string> with_value;
  std::vector<std::string> switches;
};

// Parses args into name -> value ("" for switches). Refuses unknown flags, positional
// arguments, a flag given twice, and a missing or empty value. A following argument that starts
// with "--" is a missing value; a negative number ("-1,0,0") is a value.
std::map<std::string, std::string> parse_flags(const std::vector<std::string>& args,
                                               const FlagSpec& spec);

// True when the command line asks for the help: --help or -h anywhere in it.
bool wants_help(const std::vector<std::string>& args);

// Parses the flags and the job ID: the one argument that is neither a flag nor a flag's value.
// Flag errors come first, so `--bogus 1` is reported as an unknown flag, not as a second ID.
// UsageError for a missing, empty or second ID.
std::pair<std::string, std::map<std::string, std::string>> parse_id_and_flags(
    const std::vector<std::string>& args, const FlagSpec& spec);

// One finite number; `expected` says what is allowed, for the error message.
double parse_number(const std::string& flag, std::string_view text, const char* expected);
// A finite number within [lo, hi].
double parse_in_range(const std::string& flag, std::string_view text, double lo, double hi,
                      const char* unit);
// A whole number within [lo, hi].
long parse_integer(const std::string& flag, std::string_view text, long lo, long hi);
// "a,b,c" -> exactly n finite numbers.
std::vector<double> parse_list(const std::string& flag, const std::string& text, std::size_t n,
                               const char* expected);

// JSON with keys in insertion order, written with arrays of numbers on one line.
using json = nlohmann::ordered_json;
void write_json(std::ostream& os, const json& j, int indent = 0);
// Parsed JSON text; null when empty, the text itself when it is not JSON.
json parse_or_text(const std::string& text);
// Rows of cells as a table, the columns padded to their widest cell (rows: not empty).
void print_table(std::ostream& os, const std::vector<std::vector<std::string>>& rows);

}  // namespace mdem::cli
