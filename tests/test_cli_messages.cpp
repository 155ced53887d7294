// What the user reads when a name is misspelt or help and versions are asked for: the
// did-you-mean of spec fields (YAML and JSON, with line and column), of flags and commands, the
// job kinds in `mdem run --help`, `mdem help --help`, `mdem --version` and `mdemd --version`.
#include <gtest/gtest.h>

#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "../client/src/flags.h"
#include "mdem/cli.h"
#include "mdem/spec.h"
#include "mdem/suggest.h"
#include "support.h"

namespace {

using mdem::testing::contains;

std::string spec_error(const std::function<void()>& parse) {
  try {
    parse();
  } catch (const mdem::spec::SpecError& e) {
    std::string text;
    for (const auto& fe : e.errors()) text += fe.field + ": " + fe.message + "\n";
    return text;
  }
  return "(accepted)";
}

std::string usage_error(const std::vector<std::string>& args, const mdem::cli::FlagSpec& spec) {
  try {
    mdem::cli::parse_flags(args, spec);
  } catch (const mdem::cli::UsageError& e) {
    return e.what();
  }
  return "(accepted)";
}

// Exit code and standard output of a shell command (standard error joined to it).
mdem::testing::CliResult shell(const std::string& cmd) {
  return mdem::testing::run_shell(cmd + " 2>&1");
}

TEST(Suggest, EditDistanceCountsInsertDeleteReplaceAndSwap) {
  // Textbook values: kitten -> sitting is 3 edits (2 replacements, 1 insertion).
  EXPECT_EQ(mdem::edit_distance("kitten", "sitting"), 3u);
  EXPECT_EQ(mdem::edit_distance("", "abc"), 3u);
  EXPECT_EQ(mdem::edit_distance("abc", ""), 3u);
  EXPECT_EQ(mdem::edit_distance("lenght_nm", "length_nm"), 1u);  // one swap of neighbours
  EXPECT_EQ(mdem::edit_distance("Layers", "layers"), 0u);        // case-blind
  EXPECT_EQ(mdem::edit_distance("ca", "abc"), 3u);  // optimal string alignment, not Damerau's 2
}

TEST(Suggest, OnlyANearAndUniqueNameIsSuggested) {
  const std::vector<std::string> fields = {"layers", "length_nm", "spacing_nm", "hold_ps"};
  EXPECT_EQ(mdem::closest_name("lenght_nm", fields), "length_nm");
  EXPECT_EQ(mdem::closest_name("layer", fields), "layers");
  EXPECT_EQ(mdem::closest_name("temperature", fields), std::nullopt);  // nothing near
  EXPECT_EQ(mdem::closest_name("ab", {"ac", "ad"}), std::nullopt);     // a tie: no guess
  EXPECT_EQ(mdem::closest_name("--jsn", {"--json", "--db"}), "--json");
  EXPECT_EQ(mdem::closest_name("--x", {"--json", "--db"}), std::nullopt);
  EXPECT_EQ(mdem::did_you_mean("lenght_nm", fields), "; did you mean length_nm?");
  EXPECT_EQ(mdem::did_you_mean("zzz", fields), "");
}

TEST(SpecMessages, MisspeltFieldsAreSuggestedWithLineAndColumn) {
  const std::string yaml =
      spec_error([] { mdem::spec::parse_yaml("name: x\ntwist:\n  layers: 2\n  lenght_nm: 13\n"); });
  EXPECT_TRUE(contains(yaml, "twist.lenght_nm (line 4, column 3)")) << yaml;
  EXPECT_TRUE(contains(yaml, "did you mean length_nm?")) << yaml;
  EXPECT_TRUE(contains(yaml, "allowed: layers, length_nm")) << yaml;

  const std::string json =
      spec_error([] { mdem::spec::parse_json("{\"twist\": {\n  \"hold_sp\": 4}}"); });
  EXPECT_TRUE(contains(json, "(line 2, column 3)")) << json;
  EXPECT_TRUE(contains(json, "did you mean hold_ps?")) << json;

  // A misspelt kind at the top, and a name too far from any field: no guess.
  EXPECT_TRUE(
      contains(spec_error([] { mdem::spec::parse_yaml("twsit: {}\n"); }), "did you mean twist?"));
  const std::string far = spec_error([] { mdem::spec::parse_yaml("twist: {colour: red}\n"); });
  EXPECT_TRUE(contains(far, "unknown field \"colour\"")) << far;
  EXPECT_FALSE(contains(far, "did you mean")) << far;

  // A value of the wrong type is said in words: the field, the value, what is expected.
  const std::string type = spec_error([] { mdem::spec::parse_yaml("twist:\n  layers: two\n"); });
  EXPECT_TRUE(contains(type, "twist.layers (line 2, column 3)")) << type;
  EXPECT_TRUE(contains(type, "invalid value \"two\": not a whole number")) << type;
  EXPECT_FALSE(contains(type, "TYPE_")) << type;
}

TEST(FlagMessages, MisspeltFlagsAndCommandsAreSuggested) {
  const mdem::cli::FlagSpec spec{{"--length", "--layers", "--db"}, {"--json"}};
  std::string e = usage_error({"--lenght", "3"}, spec);
  EXPECT_TRUE(contains(e, "unknown flag '--lenght'; did you mean --length?")) << e;
  e = usage_error({"--jsno"}, spec);
  EXPECT_TRUE(contains(e, "did you mean --json?")) << e;
  e = usage_error({"--zzzzzz"}, spec);
  EXPECT_FALSE(contains(e, "did you mean")) << e;
  EXPECT_TRUE(contains(e, "allowed: --length, --layers, --db, --json, --help")) << e;

  std::ostringstream out, err;
  EXPECT_EQ(mdem::cli::run({"twsit"}, out, err), mdem::cli::kUsage);
  EXPECT_TRUE(contains(err.str(), "did you mean twist?")) << err.str();
  const auto r = shell(std::string(MDEM_CLI_PATH) + " sumbit");
  EXPECT_EQ(r.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(r.out, "unknown command 'sumbit'; did you mean submit?")) << r.out;
}

TEST(HelpAndVersion, RunHelpListsTheKindsAndEveryVersionFlagWorks) {
  std::ostringstream out, err;
  ASSERT_EQ(mdem::cli::run({"--help"}, out, err), mdem::cli::kOk) << err.str();
  for (const char* kind : {"twist", "compression", "tensile", "bundle"})
    EXPECT_TRUE(contains(out.str(), std::string("\n  ") + kind + " ")) << kind << "\n" << out.str();
  EXPECT_TRUE(contains(out.str(), "Twists a hexagonal rope")) << out.str();
  EXPECT_FALSE(contains(out.str(), "--bundle-spin")) << out.str();  // not the bundle's help

  auto r = shell(std::string(MDEM_CLI_PATH) + " help --help");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(contains(r.out, "Usage: mdem <command>")) << r.out;
  r = shell(std::string(MDEM_CLI_PATH) + " --version");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.rfind("mdem ", 0), 0u) << r.out;
  r = shell(std::string(MDEMD_PATH) + " --version");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.rfind("mdemd ", 0), 0u) << r.out;
  EXPECT_FALSE(contains(r.out, "unknown")) << r.out;  // the build's version, not a placeholder
  r = shell(std::string(MDEMD_PATH) + " --help");
  EXPECT_TRUE(contains(r.out, "--version")) << r.out;
}

}  // namespace
