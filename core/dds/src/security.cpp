// DDS-Security properties of a node's participant (docs/security.md). Property names are
// those of Fast DDS 2.9.1's builtin plugins (PKI-DH, Access-Permissions, AES-GCM-GMAC).
#include "security_properties.hpp"

#include <array>
#include <filesystem>
#include <fstream>
#include <utility>

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>

#include "handshare/dds/participant.hpp"

namespace handshare::dds {

namespace {

// Role prefix of a participant name -> enclave of that role (stations of one role share it
// unless the role has one identity per station).
struct RoleEnclave {
  const char* role;
  const char* enclave;  // nullptr: "<enclave prefix>/<station>"
  const char* per_station_prefix;
};
constexpr std::array<RoleEnclave, 7> kRoles{{
    {"world_server", "world_server", nullptr},
    {"haptic_node", nullptr, "haptic/"},
    {"graphics_node", "spectator", nullptr},
    {"audio_guide", "audio_guide", nullptr},
    {"session_record", "recorder", nullptr},
    {"session_play", "player", nullptr},
    {"web_console", "web_console", nullptr},
}};

std::pair<std::string, std::string> SplitRole(const std::string& name) {
  const auto slash = name.find('/');
  if (slash == std::string::npos) return {name, ""};
  return {name.substr(0, slash), name.substr(slash + 1)};
}

std::string Readable(const std::filesystem::path& file, const std::string& what) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    throw DdsError("security: " + what + " " + file.string() + " not found");
  }
  if (!std::ifstream(file).good()) throw DdsError("security: cannot read " + what + " " + file.string());
  return std::filesystem::absolute(file).lexically_normal().string();
}

}  // namespace

std::string EnclaveOf(const std::string& participant_name) {
  const auto [role, station] = SplitRole(participant_name);
  for (const RoleEnclave& r : kRoles) {
    if (role != r.role) continue;
    if (r.enclave != nullptr) return r.enclave;
    if (station.empty()) throw DdsError("security: participant '" + participant_name + "' names no station");
    return r.per_station_prefix + station;
  }
  return participant_name;
}

std::string AnnouncedName(const std::string& participant_name) { return SplitRole(participant_name).first; }

SecurityFiles FindSecurityFiles(const std::string& dir, const std::string& participant_name) {
  const std::filesystem::path root(dir);
  std::error_code ec;
  if (!std::filesystem::is_directory(root, ec)) {
    throw DdsError("security: keystore " + dir + " is not a folder (make one with deploy/security/make_keystore.sh)");
  }
  SecurityFiles f;
  f.enclave = EnclaveOf(participant_name);
  const std::filesystem::path enclave = root / "enclaves" / f.enclave;
  if (!std::filesystem::is_directory(enclave, ec)) {
    throw DdsError("security: no identity for '" + participant_name + "' in " + dir + " (" + enclave.string() +
                   " not found)");
  }
  f.ca = Readable(root / "public" / "ca.cert.pem", "CA certificate");
  // A separate permissions CA, as sros2 keystores allow; make_keystore.sh makes one CA.
  const std::filesystem::path permissions_ca = root / "public" / "permissions_ca.cert.pem";
  f.permissions_ca = std::filesystem::exists(permissions_ca, ec) ? Readable(permissions_ca, "permissions CA") : f.ca;
  f.governance = Readable(root / "public" / "governance.p7s", "governance");
  f.crl = Readable(root / "public" / "crl.pem", "certificate revocation list");
  f.certificate = Readable(enclave / "cert.pem", "certificate");
  f.private_key = Readable(enclave / "key.pem", "private key");
  f.permissions = Readable(enclave / "permissions.p7s", "permissions");
  return f;
}

namespace detail {

constexpr std::uint32_t kSecuredUdpMessageSize = 65500;  // Fast DDS's UDPv4 default

void ApplySecurity(const std::string& dir, const std::string& participant_name,
                   eprosima::fastdds::dds::DomainParticipantQos& qos) {
  const SecurityFiles f = FindSecurityFiles(dir, participant_name);
  auto& p = qos.properties().properties();
  const auto set = [&p](const std::string& name, const std::string& value) { p.emplace_back(name, value); };
  const auto uri = [](const std::string& path) { return "file://" + path; };
  set("dds.sec.auth.plugin", "builtin.PKI-DH");
  set("dds.sec.auth.builtin.PKI-DH.identity_ca", uri(f.ca));
  set("dds.sec.auth.builtin.PKI-DH.identity_certificate", uri(f.certificate));
  set("dds.sec.auth.builtin.PKI-DH.private_key", uri(f.private_key));
  // Revoked stations: checked against every peer's certificate in the handshake.
  set("dds.sec.auth.builtin.PKI-DH.identity_crl", uri(f.crl));
  set("dds.sec.access.plugin", "builtin.Access-Permissions");
  set("dds.sec.access.builtin.Access-Permissions.permissions_ca", uri(f.permissions_ca));
  set("dds.sec.access.builtin.Access-Permissions.governance", uri(f.governance));
  set("dds.sec.access.builtin.Access-Permissions.permissions", uri(f.permissions));
  set("dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC");
  // Participant announcements travel in clear: the role, not the user.
  qos.name(AnnouncedName(participant_name));
  // The handshake's messages (certificates, permissions: several kB) are never fragmented: a
  // UDP transport limited to 1400-byte messages (the QoS file's, so that one lost packet costs
  // one fragment of a field) cannot send them ("Cannot serialize ParticipantGenericMessage"),
  // and no secured participant ever authenticates. A secured participant's UDP messages keep
  // Fast DDS's default size (a copy: the profile's descriptor serves unsecured participants too).
  for (auto& transport : qos.transport().user_transports) {
    const auto udp = std::dynamic_pointer_cast<eprosima::fastdds::rtps::UDPv4TransportDescriptor>(transport);
    if (udp && udp->maxMessageSize < kSecuredUdpMessageSize) {
      auto whole = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>(*udp);
      whole->maxMessageSize = kSecuredUdpMessageSize;
      transport = whole;
    }
  }
}

std::string SecurityFailureHint(const std::string& security_dir, const std::string& participant_name) {
  if (security_dir.empty()) return "";
  return " with identity '" + EnclaveOf(participant_name) + "' of keystore " + security_dir +
         ": its certificate is expired, not yet valid, revoked or not signed by the keystore's CA, "
         "or its governance or permissions are not signed by that CA or do not grant it (the "
         "security log lines above say which)";
}

}  // namespace detail
}  // namespace handshare::dds
