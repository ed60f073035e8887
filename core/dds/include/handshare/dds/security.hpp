#pragma once
/// DDS-Security for a node's participant: which identity (enclave) of a keystore made by
/// deploy/security/make_keystore.sh a participant uses, and where its files are. The
/// properties themselves are set in security.cpp (docs/security.md).
#include <string>

namespace handshare::dds {

/// The files a secured participant reads (absolute paths).
struct SecurityFiles {
  std::string enclave;          ///< e.g. "haptic/alice"
  std::string ca;               ///< public/ca.cert.pem: identity CA (and permissions CA)
  std::string permissions_ca;   ///< public/permissions_ca.cert.pem if there is one, else ca
  std::string governance;       ///< public/governance.p7s
  std::string crl;              ///< public/crl.pem: revoked certificates
  std::string certificate;      ///< enclaves/<enclave>/cert.pem
  std::string private_key;      ///< enclaves/<enclave>/key.pem
  std::string permissions;      ///< enclaves/<enclave>/permissions.p7s
};

/// The enclave of a node's participant, from the role prefix of its name: "world_server" ->
/// "world_server", "haptic_node/alice" -> "haptic/alice", "graphics_node/..." -> "spectator",
/// "audio_guide/..." -> "audio_guide", "session_record" -> "recorder", "session_play" ->
/// "player", "web_console/..." -> "web_console"; any other name is taken as the enclave path
/// itself.
std::string EnclaveOf(const std::string& participant_name);

/// The name a secured participant announces in clear (DDS discovery): its role only
/// ("haptic_node/alice" -> "haptic_node"), so no station or user name travels unencrypted
/// beyond the certificate subjects (docs/security.md).
std::string AnnouncedName(const std::string& participant_name);

/// The files of participant_name's enclave in the keystore dir. Throws DdsError naming the
/// first file that is missing or unreadable.
SecurityFiles FindSecurityFiles(const std::string& dir, const std::string& participant_name);

}  // namespace handshare::dds
