#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "test_support.hpp"

namespace inhand {
namespace {

using Json = nlohmann::json;

Json ModelJson(const std::string& args, int expected_joints) {
  const test::CommandResult r = test::RunInhand("model " + args + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const Json j = Json::parse(r.output);
  EXPECT_EQ(j.at("joints").size(), static_cast<std::size_t>(expected_joints)) << args;
  for (const Json& joint : j.at("joints")) {
    EXPECT_TRUE(joint.contains("name") && joint.contains("type") && joint.contains("lower") && joint.contains("upper"));
  }
  EXPECT_GT(j.at("pieces").get<int>(), 0);
  EXPECT_GT(j.at("triangles").get<int>(), 0);
  EXPECT_FALSE(j.at("links").empty());
  return j;
}

TEST(Cli, ModelOnTheProjectHand) {
  const Json j = ModelJson(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), 16);
  EXPECT_EQ(j.at("joints")[0].at("name"), "index_abduction");
  EXPECT_EQ(j.at("palm_link"), "palm");
  const test::CommandResult text = test::RunInhand("model " + test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"));
  EXPECT_EQ(text.exit_code, 0);
  EXPECT_NE(text.output.find("16 joints"), std::string::npos);
}

TEST(Cli, ModelOnEverySharedHand) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const std::string hands = test::SharedAssets() + "/hands/";
  const std::vector<std::pair<std::string, int>> urdfs = {
      {"allegro_hand/allegro_hand_left.urdf", 16},  {"allegro_hand/allegro_hand_left_glb.urdf", 16},
      {"allegro_hand/allegro_hand_right.urdf", 16}, {"allegro_hand/allegro_hand_right_glb.urdf", 16},
      {"allegro_hand_description/allegro_hand_description_left.urdf", 16},
      {"allegro_hand_description/allegro_hand_description_right.urdf", 16},
      {"barrett_hand/bhand_model.urdf", 8},         {"barrett_hand/bhand_model_glb.urdf", 8},
      {"shadow_hand/shadow_hand_left.urdf", 24},    {"shadow_hand/shadow_hand_left_glb.urdf", 24},
      {"shadow_hand/shadow_hand_right.urdf", 24},   {"shadow_hand/shadow_hand_right_glb.urdf", 24}};
  for (const auto& [urdf, n] : urdfs) ModelJson(hands + urdf, n);
  // The original Allegro description with an explicit package map too.
  ModelJson(hands + "allegro_hand_description/allegro_hand_description_right.urdf --package allegro_hand_description=" +
                hands + "allegro_hand_description",
            16);
}

TEST(Cli, ModelOnObjects) {
  const test::CommandResult r = test::RunInhand("model " + test::ProjectAsset("objects/brush/object.json") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json j = Json::parse(r.output);
  EXPECT_EQ(j.at("name"), "brush");
  EXPECT_EQ(j.at("pieces"), 3);
  EXPECT_EQ(j.at("tags").size(), 1u);
}

TEST(Cli, BadInputExitsNonZeroWithOneClearLine) {
  test::TempDir dir;
  dir.Write("bad.urdf", "<robot name='x'>\n<link name='a'>\n");
  for (const std::string& args : {"model " + (dir / "bad.urdf"), "model " + (dir / "missing.urdf"),
                                  "model " + (dir / "bad.urdf") + " --package nonsense"}) {
    const test::CommandResult r = test::RunInhand(args);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_NE(r.output.find("inhand: error: "), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("terminate"), std::string::npos);  // never a crash
  }
  EXPECT_NE(test::RunInhand("no-such-command").exit_code, 0);
}

}  // namespace
}  // namespace inhand
