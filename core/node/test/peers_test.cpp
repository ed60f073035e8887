#include "handshare/node/peers.hpp"

#include <gtest/gtest.h>

#include <string>

#include "handshare/common/options.hpp"

namespace handshare::node {
namespace {

// The message of the OptionError that ParsePeers throws for list ("" when none).
std::string ErrorOf(const std::string& list) {
  try {
    ParsePeers(list);
  } catch (const common::OptionError& e) {
    return e.what();
  }
  return "";
}

TEST(Peers, ParsesAddressesPortsAndLocalhost) {
  EXPECT_TRUE(ParsePeers("").empty());
  const auto peers = ParsePeers("10.1.2.3,192.168.0.7:7412,localhost");
  ASSERT_EQ(peers.size(), 3u);
  EXPECT_EQ(peers[0].ipv4, "10.1.2.3");
  EXPECT_EQ(peers[0].port, 0);  // every participant of the domain on that host
  EXPECT_EQ(peers[1].ipv4, "192.168.0.7");
  EXPECT_EQ(peers[1].port, 7412);
  EXPECT_EQ(peers[1].text, "192.168.0.7:7412");
  EXPECT_EQ(peers[2].ipv4, "127.0.0.1");  // a name, resolved
}

TEST(Peers, BadEntriesNameTheOptionAndTheValue) {
  for (const std::string bad : {"10.0.0.1:", "10.0.0.1:99999", "10.0.0.1:0", "10.0.0.1:74x0", "10.0.0.1,,10.0.0.2",
                                ",", ":7400", "::1", "[::1]:7400", "no-such-host.invalid", "a b"}) {
    const std::string message = ErrorOf(bad);
    ASSERT_FALSE(message.empty()) << bad << " was accepted";
    EXPECT_NE(message.find("--peers"), std::string::npos) << message;
  }
  EXPECT_NE(ErrorOf("10.0.0.1:99999").find("'10.0.0.1:99999': port 99999 is not in 1..65535"), std::string::npos);
  EXPECT_NE(ErrorOf("no-such-host.invalid").find("cannot resolve host 'no-such-host.invalid'"), std::string::npos);
  EXPECT_NE(ErrorOf("10.0.0.1,,10.0.0.2").find("'': empty entry"), std::string::npos);
  EXPECT_NE(ErrorOf("::1").find("IPv6"), std::string::npos);
}

}  // namespace
}  // namespace handshare::node
