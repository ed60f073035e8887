// Which identity a participant takes from a keystore, and the errors a bad keystore gives.
// (Joining with a real keystore, and what outsiders see, is tests/security_test.py's.)
#include "handshare/dds/security.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include "handshare/dds/participant.hpp"

namespace handshare::dds {
namespace {

TEST(Security, EnclaveFollowsTheRoleOfTheParticipantName) {
  EXPECT_EQ(EnclaveOf("world_server"), "world_server");
  EXPECT_EQ(EnclaveOf("haptic_node/alice"), "haptic/alice");
  EXPECT_EQ(EnclaveOf("graphics_node/graphics-42"), "spectator");
  EXPECT_EQ(EnclaveOf("graphics_node/lobby"), "spectator");
  EXPECT_EQ(EnclaveOf("audio_guide/audio-7"), "audio_guide");
  EXPECT_EQ(EnclaveOf("session_record"), "recorder");
  EXPECT_EQ(EnclaveOf("session_play"), "player");
  // One identity for every console: its grant, not its --name, decides what it may write.
  EXPECT_EQ(EnclaveOf("web_console/web-console"), "web_console");
  EXPECT_EQ(EnclaveOf("web_console/operator-console"), "web_console");
  EXPECT_EQ(EnclaveOf("probe"), "probe");  // anything else: the enclave path itself
  EXPECT_THROW(EnclaveOf("haptic_node"), DdsError);  // a haptic identity is per user
}

TEST(Security, AnnouncedNameCarriesNoStation) {
  EXPECT_EQ(AnnouncedName("haptic_node/alice"), "haptic_node");
  EXPECT_EQ(AnnouncedName("world_server"), "world_server");
  EXPECT_EQ(AnnouncedName("web_console/operator-console"), "web_console");
}

class Keystore : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("handshare-keystore-" + std::to_string(getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_ / "public");
    std::filesystem::create_directories(dir_ / "enclaves" / "haptic" / "alice");
    for (const char* f : {"public/ca.cert.pem", "public/governance.p7s", "public/crl.pem",
                          "enclaves/haptic/alice/cert.pem", "enclaves/haptic/alice/key.pem",
                          "enclaves/haptic/alice/permissions.p7s"}) {
      std::ofstream(dir_ / f) << "x";
    }
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Error(const std::string& name) {
    try {
      FindSecurityFiles(dir_.string(), name);
    } catch (const DdsError& e) {
      return e.what();
    }
    return "";
  }
  std::filesystem::path dir_;
};

TEST_F(Keystore, FindsEveryFileOfTheEnclave) {
  const SecurityFiles f = FindSecurityFiles(dir_.string(), "haptic_node/alice");
  EXPECT_EQ(f.enclave, "haptic/alice");
  EXPECT_EQ(f.certificate, (dir_ / "enclaves/haptic/alice/cert.pem").string());
  EXPECT_EQ(f.permissions, (dir_ / "enclaves/haptic/alice/permissions.p7s").string());
  EXPECT_EQ(f.crl, (dir_ / "public/crl.pem").string());
  EXPECT_EQ(f.permissions_ca, f.ca);  // one CA for both unless the keystore has two
  std::ofstream(dir_ / "public/permissions_ca.cert.pem") << "x";
  EXPECT_EQ(FindSecurityFiles(dir_.string(), "haptic_node/alice").permissions_ca,
            (dir_ / "public/permissions_ca.cert.pem").string());
}

TEST_F(Keystore, AMissingFileIsNamed) {
  std::filesystem::remove(dir_ / "enclaves/haptic/alice/key.pem");
  EXPECT_NE(Error("haptic_node/alice").find("private key " + (dir_ / "enclaves/haptic/alice/key.pem").string() +
                                            " not found"),
            std::string::npos)
      << Error("haptic_node/alice");
  std::filesystem::remove(dir_ / "public/crl.pem");
  EXPECT_NE(Error("haptic_node/alice").find("crl.pem not found"), std::string::npos);
}

TEST_F(Keystore, AMissingIdentityOrKeystoreIsNamed) {
  EXPECT_NE(Error("haptic_node/bob").find("no identity for 'haptic_node/bob'"), std::string::npos);
  EXPECT_NE(Error("haptic_node/bob").find("enclaves/haptic/bob not found"), std::string::npos);
  std::filesystem::remove_all(dir_);
  EXPECT_NE(Error("haptic_node/alice").find("is not a folder"), std::string::npos);
}

TEST_F(Keystore, AParticipantWithABadKeystoreFailsNamingTheFile) {
  std::filesystem::remove(dir_ / "public/governance.p7s");
  try {
    Participant p(149, "s", "haptic_node/alice", "", dir_.string());
    FAIL() << "a participant was created without its governance";
  } catch (const DdsError& e) {
    EXPECT_NE(std::string(e.what()).find("governance.p7s not found"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace handshare::dds
