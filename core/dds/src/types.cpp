// The registry of message types: maps each generated type to its name and type support.
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <handshare/idl/handshare.h>
#include <handshare/idl/handsharePubSubTypes.h>

#include "handshare/dds/messages.hpp"

namespace handshare::dds::detail {

#define HANDSHARE_DDS_TYPE(T)                                                        \
  template <>                                                                        \
  const char* TypeOf<msg::T>::Name() {                                               \
    return "handshare::msg::" #T;                                                    \
  }                                                                                  \
  template <>                                                                        \
  std::shared_ptr<void> TypeOf<msg::T>::MakeSupport() {                              \
    return std::make_shared<eprosima::fastdds::dds::TypeSupport>(new msg::T##PubSubType()); \
  }

HANDSHARE_DDS_TYPE(MemberInfo)
HANDSHARE_DDS_TYPE(SceneState)
HANDSHARE_DDS_TYPE(DeviceState)
HANDSHARE_DDS_TYPE(ContactSet)
HANDSHARE_DDS_TYPE(Deformation)
HANDSHARE_DDS_TYPE(ObjectState)
HANDSHARE_DDS_TYPE(ControlEvent)
HANDSHARE_DDS_TYPE(VisitAnswers)
HANDSHARE_DDS_TYPE(OperatorCommand)
HANDSHARE_DDS_TYPE(MessageBoard)
HANDSHARE_DDS_TYPE(ControlState)
HANDSHARE_DDS_TYPE(SessionRoster)
HANDSHARE_DDS_TYPE(LoopStatistics)
HANDSHARE_DDS_TYPE(DeskInput)

#undef HANDSHARE_DDS_TYPE

}  // namespace handshare::dds::detail

// Serialization for recordings (serialization.hpp): the same CDR the PubSubTypes put on the wire,
// written through Fast CDR here so that a bad payload can say where it stopped.
#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastcdr/exceptions/Exception.h>

#include "handshare/dds/serialization.hpp"

namespace handshare::dds {

template <class T>
std::vector<std::uint8_t> Serialize(const T& sample) {
  std::vector<std::uint8_t> out(T::getCdrSerializedSize(sample) + 4);
  eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(out.data()), out.size());
  eprosima::fastcdr::Cdr cdr(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
  try {
    cdr.serialize_encapsulation();
    sample.serialize(cdr);
  } catch (const eprosima::fastcdr::exception::Exception& e) {
    throw SerializationError(std::string("serializing ") + detail::TypeOf<T>::Name() + ": " + e.what(),
                             cdr.getSerializedDataLength());
  }
  out.resize(cdr.getSerializedDataLength());
  return out;
}

template <class T>
void Deserialize(std::span<const std::uint8_t> payload, T& sample) {
  // Fast CDR reads from a char*; it never writes through a buffer it only deserializes from.
  eprosima::fastcdr::FastBuffer buffer(const_cast<char*>(reinterpret_cast<const char*>(payload.data())),
                                       payload.size());
  eprosima::fastcdr::Cdr cdr(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
  const auto fail = [&](const std::string& why) {
    throw SerializationError("offset " + std::to_string(cdr.getSerializedDataLength()) + " of " +
                                 std::to_string(payload.size()) + " bytes: " + why + " (not a " +
                                 detail::TypeOf<T>::Name() + ")",
                             cdr.getSerializedDataLength());
  };
  if (payload.size() < 4) fail("shorter than the 4-byte encapsulation header");
  if (payload[0] != 0 || payload[1] > 1) fail("unknown encapsulation");
  try {
    cdr.read_encapsulation();
    sample.deserialize(cdr);
  } catch (const eprosima::fastcdr::exception::Exception& e) {
    fail(e.what());
  }
  // A sample ends at most 3 bytes of alignment before the payload does.
  if (payload.size() - cdr.getSerializedDataLength() > 3) {
    fail(std::to_string(payload.size() - cdr.getSerializedDataLength()) + " bytes left over after the sample");
  }
}

#define HANDSHARE_SERIALIZATION(T)                                                  \
  template std::vector<std::uint8_t> Serialize<msg::T>(const msg::T&);             \
  template void Deserialize<msg::T>(std::span<const std::uint8_t>, msg::T&);
HANDSHARE_SERIALIZATION(MemberInfo)
HANDSHARE_SERIALIZATION(SceneState)
HANDSHARE_SERIALIZATION(DeviceState)
HANDSHARE_SERIALIZATION(ContactSet)
HANDSHARE_SERIALIZATION(Deformation)
HANDSHARE_SERIALIZATION(ObjectState)
HANDSHARE_SERIALIZATION(ControlEvent)
HANDSHARE_SERIALIZATION(VisitAnswers)
HANDSHARE_SERIALIZATION(OperatorCommand)
HANDSHARE_SERIALIZATION(MessageBoard)
HANDSHARE_SERIALIZATION(ControlState)
HANDSHARE_SERIALIZATION(SessionRoster)
HANDSHARE_SERIALIZATION(LoopStatistics)
HANDSHARE_SERIALIZATION(DeskInput)
#undef HANDSHARE_SERIALIZATION

}  // namespace handshare::dds
