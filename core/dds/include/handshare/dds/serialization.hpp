#pragma once
/// Samples as bytes: the CDR the wire carries (4-byte encapsulation header, then the generated
/// type's XCDR1 body), for recordings (world_server's session_record / session_play).
/// Defined for every message type of handshare.idl (messages.hpp); no Fast DDS header here.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "handshare/dds/messages.hpp"

namespace handshare::dds {

/// A payload that is not a sample of the type: what() says what failed and where
/// ("offset 132 of 140 bytes: not enough data"), offset() is the byte it stopped at.
class SerializationError : public DdsError {
 public:
  SerializationError(const std::string& what, std::size_t offset) : DdsError(what), offset_(offset) {}
  std::size_t offset() const { return offset_; }

 private:
  std::size_t offset_;
};

/// The sample's CDR (encapsulation header included), exactly as many bytes as it needs.
template <class T>
std::vector<std::uint8_t> Serialize(const T& sample);

/// Reads a payload written by Serialize (or received from the wire) into `sample`. Throws
/// SerializationError for a payload that is too short, has an unknown encapsulation, or has
/// bytes left over after the sample.
template <class T>
void Deserialize(std::span<const std::uint8_t> payload, T& sample);

}  // namespace handshare::dds
