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
HANDSHARE_DDS_TYPE(MessageBoard)
HANDSHARE_DDS_TYPE(LoopStatistics)

#undef HANDSHARE_DDS_TYPE

}  // namespace handshare::dds::detail
