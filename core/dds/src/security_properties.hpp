#pragma once
// Private to the DDS layer: turns a keystore's files into the participant's DDS-Security
// properties (Fast DDS 2.9 builtin plugins).
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

#include "handshare/dds/security.hpp"

namespace handshare::dds::detail {

/// Sets the authentication (PKI-DH, with the CRL), access control (permissions) and
/// cryptography (AES-GCM-GMAC) plugins' properties and the announced name on qos.
/// Throws DdsError when a file of the enclave is missing (FindSecurityFiles).
void ApplySecurity(const std::string& dir, const std::string& participant_name,
                   eprosima::fastdds::dds::DomainParticipantQos& qos);

/// What to add to "could not create participant" when security_dir is set ("" when not):
/// the identity and what the plugins refuse at creation.
std::string SecurityFailureHint(const std::string& security_dir, const std::string& participant_name);

}  // namespace handshare::dds::detail
