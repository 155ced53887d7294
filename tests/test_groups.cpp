// Identity and groups as data: every element carries a tag given at creation, checkpoints keep
// and check the tags, and a scene's grips or a job's platens are named groups of tags.
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "mdem/core/elements.h"
#include "mdem/core/groups.h"
#include "mdem/core/units.h"
#include "mdem/io/state_io.h"
#include "mdem/job/compression_job.h"
#include "mdem/job/twist_job.h"
#include "mdem/scene/grain.h"
#include "mdem/scene/hex_rope.h"

namespace mdem {
namespace {

RopeSpec small_rope() {
  RopeSpec s;
  s.layers = 3;
  s.segments = 12;
  s.spacing = 1.72;
  s.grip_segments = 2;
  return s;
}

TEST(Tags, AreZeroToNMinusOneAfterBuildingARope) {
  Elements el;
  build_hex_rope(el, small_rope());
  ASSERT_EQ(el.tag.size(), el.size());
  for (std::size_t i = 0; i < el.size(); ++i) {
    EXPECT_EQ(el.tag[i], i);
    EXPECT_EQ(el.index_of(el.tag[i]), i);
  }
  EXPECT_EQ(el.next_tag, el.size());
  EXPECT_THROW((void)el.index_of(el.size()), std::out_of_range);
}

TEST(Tags, IndexOfFollowsAReordering) {
  Elements el;
  build_hex_rope(el, small_rope());
  // Swap the tags of two elements, as a reordering of the arrays would carry them.
  std::swap(el.tag[3], el.tag[40]);
  EXPECT_EQ(el.index_of(3), 40u);
  EXPECT_EQ(el.index_of(40), 3u);
  EXPECT_EQ(el.index_of(7), 7u);
}

TwistJobSpec twist_spec() {
  TwistJobSpec s;
  s.rope.layers = 2;
  s.rope.segments = 10;
  s.loading.torque_max = units::nNnm(1.0);
  s.loading.rate = units::nNnm(1.0);
  s.loading.hold = 1.0;
  return s;
}

IntegratorSettings two_threads() {
  IntegratorSettings st;
  st.threads = 2;
  return st;
}

TEST(Tags, CheckpointRoundTripKeepsThemAndAlteredTagsAreRefused) {
  TwistJob saved(twist_spec(), two_threads());
  saved.system().run(20);
  const std::vector<std::uint64_t> tags = saved.system().elements().tag;
  const std::string bytes = save_checkpoint(saved);

  TwistJob resumed(twist_spec(), two_threads());
  load_checkpoint(resumed, bytes);
  EXPECT_EQ(resumed.system().elements().tag, tags);

  // The same state with a tag no element of the job holds is the state of other elements: refused.
  // (Tags exchanged between elements are a memory order now, which a checkpoint may hold; with
  // the arrays in tag order, the other properties would then differ.)
  saved.system().elements().tag[0] = saved.system().elements().next_tag + 7;
  const std::string altered = save_checkpoint(saved);
  TwistJob other(twist_spec(), two_threads());
  try {
    load_checkpoint(other, altered);
    ADD_FAILURE() << "a checkpoint with altered tags was loaded";
  } catch (const CheckpointError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("'tag'"), std::string::npos) << m;
    EXPECT_NE(m.find("another scene"), std::string::npos) << m;
  }
}

TEST(Groups, HoldSortedTagsAndNameTheKnownGroupsWhenOneIsMissing) {
  Groups g;
  g.add("b", {5, 1, 3});
  g.add("a", {2});
  EXPECT_EQ(g.get("b"), (std::vector<std::uint64_t>{1, 3, 5}));
  EXPECT_EQ(g.names(), (std::vector<std::string>{"a", "b"}));
  try {
    (void)g.get("grip");
    ADD_FAILURE() << "no error for a missing group";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("no group 'grip'"), std::string::npos) << m;
    EXPECT_NE(m.find("known groups: a, b"), std::string::npos) << m;
  }
  EXPECT_THROW(g.add("a", {7}), std::invalid_argument);        // declared twice
  EXPECT_THROW(g.add("", {7}), std::invalid_argument);         // no name
  EXPECT_THROW(g.add("c", {}), std::invalid_argument);         // no element
  EXPECT_THROW(g.add("c", {4, 2, 4}), std::invalid_argument);  // a tag twice
  EXPECT_FALSE(g.has("c"));
}

// The grips hold exactly the grip_segments end segments of every tube: 2 per tube per end,
// indices 0, 1 at end a and n−2, n−1 at end b, one of each per tube.
TEST(Groups, RopeGripsHoldExactlyTheEndSegmentsOfEveryTube) {
  Elements el;
  const RopeSpec spec = small_rope();
  const Rope rope = build_hex_rope(el, spec);
  const int n = spec.segments;
  for (std::string_view name : {kRopeGripA, kRopeGripB}) {
    const std::vector<std::size_t> grip = el.group_indices(name);
    EXPECT_EQ(grip.size(), 2 * rope.tubes.size()) << name;
    std::vector<std::vector<int>> per_tube(rope.tubes.size());
    for (std::size_t i : grip) {
      ASSERT_EQ(el.kind[i], ElementKind::CntSegment);
      per_tube.at(static_cast<std::size_t>(el.tube[i])).push_back(el.index[i]);
    }
    const std::vector<int> want =
        name == kRopeGripA ? std::vector<int>{0, 1} : std::vector<int>{n - 2, n - 1};
    for (auto& t : per_tube) {
      std::sort(t.begin(), t.end());
      EXPECT_EQ(t, want) << name;
    }
  }
}

TEST(Groups, PlatenGroupHoldsExactlyTheWallElements) {
  CompressionJobSpec s;
  s.particle.r_outer = 6.0;
  s.particle.grain_r_min = 1.0;
  s.particle.grain_r_max = 2.0;
  s.particle.target_porosity = 0.4;
  s.particle.material = gold();
  s.particle.seed = 1;
  s.loading.speed = 0.02;
  s.loading.peak_displacement = 1.0;
  CompressionJob job(s, two_threads());
  prepare_job(job);  // packs the particle and builds the system with its platens
  const Elements& el = job.system().elements();
  std::vector<std::size_t> walls;
  for (std::size_t i = 0; i < el.size(); ++i)
    if (el.kind[i] == ElementKind::Wall) walls.push_back(i);
  EXPECT_EQ(walls.size(), 2u);
  EXPECT_EQ(el.group_indices(kPlatens), walls);
  // The top platen is the wall above the grains, facing down (−z); the bottom one faces up.
  const std::size_t top = el.group_indices(kTopPlaten).at(0);
  const std::size_t bottom = el.group_indices(kBottomPlaten).at(0);
  EXPECT_GT(el.x[top].z(), el.x[bottom].z());
  EXPECT_NEAR((el.q[top] * Vec3::UnitZ()).z(), -1.0, 1e-12);
  EXPECT_NEAR((el.q[bottom] * Vec3::UnitZ()).z(), 1.0, 1e-12);
}

}  // namespace
}  // namespace mdem
