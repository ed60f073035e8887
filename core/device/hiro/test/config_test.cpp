#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "handshare/hiro/hiro_model.hpp"

namespace handshare::hiro {
namespace {

std::string ConfigText() {
  std::ifstream in(HANDSHARE_HIRO_CONFIG);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Parses the shipped config after `edit` and returns the error message ("" if none).
template <typename Edit>
std::string ErrorAfter(Edit edit) {
  nlohmann::json j = nlohmann::json::parse(ConfigText());
  edit(j);
  try {
    HiroModel::Parse(j.dump(), "edited.json");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(HiroConfig, ShippedFileLoadsWithTheSourcedValues) {
  const HiroModel m = HiroModel::Load(HANDSHARE_HIRO_CONFIG);
  constexpr double kDeg = M_PI / 180.0;
  EXPECT_DOUBLE_EQ(m.arm.joint[1].min_rad, 0.0);
  EXPECT_DOUBLE_EQ(m.arm.joint[2].min_rad, -90 * kDeg);
  EXPECT_DOUBLE_EQ(m.arm.joint[2].max_rad, 55 * kDeg);
  EXPECT_DOUBLE_EQ(m.finger[1].joint[2].max_rad, 114 * kDeg);
  EXPECT_DOUBLE_EQ(m.finger[0].joint[0].min_rad, -40 * kDeg);  // thumb
  EXPECT_DOUBLE_EQ(m.finger[0].joint[1].max_rad, 103 * kDeg);
  EXPECT_DOUBLE_EQ(m.finger[3].joint[0].max_torque_N_m, 0.81);
  EXPECT_DOUBLE_EQ(m.finger[3].joint[2].max_speed_rad_per_s, 9.2);
  EXPECT_DOUBLE_EQ(m.max_fingertip_force_N, 3.5);
  EXPECT_DOUBLE_EQ(m.control_rate_Hz, 1000.0);
  // Masses add up to the sourced totals: 5 x 0.13 + palm = 0.73, arm links = 6.9.
  double hand = m.palm_mass_kg;
  for (const auto& f : m.finger) hand += f.link_mass_kg[0] + f.link_mass_kg[1] + f.link_mass_kg[2];
  EXPECT_NEAR(hand, 0.73, 1e-12);
  EXPECT_NEAR(m.arm.upper_arm_mass_kg + m.arm.forearm_mass_kg + m.arm.wrist_mass_kg, 6.9, 1e-12);
}

TEST(HiroConfig, MissingFileIsNamed) {
  try {
    HiroModel::Load("/nonexistent/hiro2.json");
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/hiro2.json"), std::string::npos) << e.what();
  }
}

// The ConfigError Parse throws for `text` ("" and a test failure if it throws none).
std::string ParseError(const std::string& text, const std::string& origin) {
  try {
    HiroModel::Parse(text, origin);
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected ConfigError for " << text;
  return "";
}

TEST(HiroConfig, BadJsonNamesTheFile) {
  const std::string e = ParseError("{ \"format\": ", "broken.json");
  EXPECT_NE(e.find("broken.json"), std::string::npos) << e;
}

// A number beyond double's range is nlohmann's out_of_range, not a parse_error (found by the
// hiro_config fuzz target): refused as bad JSON, naming the file.
TEST(HiroConfig, ANumberTooLargeForADoubleIsRefusedNamingTheFile) {
  const std::string e = ParseError("{ \"format\": 1e999 }", "huge.json");
  EXPECT_NE(e.find("huge.json: not valid JSON"), std::string::npos) << e;
  EXPECT_NE(e.find("number overflow"), std::string::npos) << e;
}

TEST(HiroConfig, ErrorsNameFileAndField) {
  struct Case {
    const char* pointer;
    nlohmann::json value;  // null: remove the field
    const char* says;
  };
  const Case cases[] = {
      {"/sourced/arm/forearm_m", nullptr, "missing"},
      {"/sourced/arm/forearm_m", "0.31", "expected a number"},
      {"/sourced/arm/upper_arm_m", -0.3, "outside"},
      {"/sourced/hand/max_joint_torque_N_m/1", 0.0, "outside"},
      {"/sourced/arm/joint_range_deg/2", nlohmann::json::array({55, -90}), "range minimum"},
      {"/sourced/hand/finger_joint_range_deg/0", nlohmann::json::array({-30}), "array of 2"},
      {"/assumed/hand/finger_link_m", nlohmann::json::array({0.002, 0.07}), "array of 3"},
      {"/assumed/arm/joint_axis_B/3", nlohmann::json::array({0, 2, 0}), "outside"},
      {"/assumed/arm/joint_axis_B/3", nlohmann::json::array({0, 0.5, 0}), "unit vector"},
      {"/assumed/arm/home_deg/2", 80, "outside the joint range"},
      {"/assumed/hand/palm_mass_kg", 0.5, "must add up"},
      {"/assumed/arm_following/rate_per_s", nullptr, "missing"},
      {"/assumed/arm_following/finger_weight", nlohmann::json::array({0, 0, 0, 0, 0}), "at least one weight"},
      {"/sourced/arm/joint_range_deg/3", nlohmann::json::array({16, 24}), "leaves no room"},
      {"/sourced/arm/max_hand_speed_m_per_s", 0.0, "outside"},
      {"/format", "something-else", "handshare-hiro-v1"},
  };
  for (const Case& c : cases) {
    const std::string msg = ErrorAfter([&](nlohmann::json& j) {
      const nlohmann::json::json_pointer p(c.pointer);
      if (c.value.is_null()) {
        j.at(p.parent_pointer()).erase(p.back());
      } else {
        j[p] = c.value;
      }
    });
    EXPECT_NE(msg.find("edited.json"), std::string::npos) << c.pointer << ": " << msg;
    // The field named is the one edited, or for whole-array checks the array itself.
    EXPECT_NE(msg.find(std::string(c.pointer).substr(0, std::string(c.pointer).find_last_of('/'))), std::string::npos)
        << c.pointer << ": " << msg;
    EXPECT_NE(msg.find(c.says), std::string::npos) << c.pointer << ": " << msg;
  }
}

}  // namespace
}  // namespace handshare::hiro
