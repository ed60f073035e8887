#pragma once
/// The generated message types (handshare.idl) and their registration with the DDS layer.
/// Node libraries include this; they never include Fast DDS headers themselves.
#include <handshare/idl/handshare.h>

#include <array>
#include <functional>
#include <string>
#include <type_traits>

#include "handshare/common/hand.hpp"
#include "handshare/dds/participant.hpp"
#include "handshare/dds/topics.hpp"

namespace handshare::dds {

// One finger count and one joint count: the models' (handshare/common/hand.hpp) are the
// messages' (handshare.idl names them once as constants and sizes its arrays with them).
static_assert(common::kFingers == msg::kFingers, "handshare.idl kFingers != common::kFingers");
static_assert(common::kHandJoints == msg::kHandJoints, "handshare.idl kHandJoints != common::kHandJoints");
static_assert(common::kArmJoints == msg::kArmJoints, "handshare.idl kArmJoints != common::kArmJoints");
static_assert(std::tuple_size_v<std::remove_cvref_t<decltype(msg::DeviceState().q_hand_rad())>> == common::kHandJoints,
              "DeviceState::q_hand_rad has not kHandJoints angles");
static_assert(std::tuple_size_v<std::remove_cvref_t<decltype(msg::DeviceState().q_arm_rad())>> == common::kArmJoints,
              "DeviceState::q_arm_rad has not kArmJoints angles");
static_assert(std::tuple_size_v<std::remove_cvref_t<decltype(msg::DeviceState().p_WE_m())>> == common::kFingers,
              "DeviceState::p_WE_m has not kFingers fingertips");
static_assert(std::tuple_size_v<std::remove_cvref_t<decltype(msg::DeviceState().f_E_W_N())>> == common::kFingers,
              "DeviceState::f_E_W_N has not kFingers fingertips");
static_assert(std::tuple_size_v<std::remove_cvref_t<decltype(msg::ContactSet().fingers())>> == common::kFingers,
              "ContactSet::fingers has not kFingers fingers");

namespace detail {
#define HANDSHARE_DECLARE_DDS_TYPE(T)                  \
  template <>                                          \
  const char* TypeOf<msg::T>::Name();                  \
  template <>                                          \
  std::shared_ptr<void> TypeOf<msg::T>::MakeSupport();
HANDSHARE_DECLARE_DDS_TYPE(MemberInfo)
HANDSHARE_DECLARE_DDS_TYPE(SceneState)
HANDSHARE_DECLARE_DDS_TYPE(DeviceState)
HANDSHARE_DECLARE_DDS_TYPE(ContactSet)
HANDSHARE_DECLARE_DDS_TYPE(Deformation)
HANDSHARE_DECLARE_DDS_TYPE(ObjectState)
HANDSHARE_DECLARE_DDS_TYPE(ControlEvent)
HANDSHARE_DECLARE_DDS_TYPE(VisitAnswers)
HANDSHARE_DECLARE_DDS_TYPE(OperatorCommand)
HANDSHARE_DECLARE_DDS_TYPE(MessageBoard)
HANDSHARE_DECLARE_DDS_TYPE(ControlState)
HANDSHARE_DECLARE_DDS_TYPE(SessionRoster)
HANDSHARE_DECLARE_DDS_TYPE(LoopStatistics)
HANDSHARE_DECLARE_DDS_TYPE(DeskInput)
#undef HANDSHARE_DECLARE_DDS_TYPE
}  // namespace detail

/// A writer for a topic of topics.hpp with its writer profile.
template <class T>
Writer<T> MakeWriter(Participant& p, const topics::TopicSpec& spec) {
  return p.CreateWriter<T>(spec.name, spec.writer_profile);
}
/// A reader for a topic of topics.hpp with its reader profile.
template <class T>
Reader<T> MakeReader(Participant& p, const topics::TopicSpec& spec) {
  return p.CreateReader<T>(spec.name, spec.reader_profile);
}
/// The same for a topic a node can do without: under DDS-Security a keystore made before its
/// role was granted the topic refuses the reader. Then `say` is told why and what the node
/// does without it (`without`), and the reader is empty (test it with operator bool).
template <class T>
Reader<T> MakeReaderIfGranted(Participant& p, const topics::TopicSpec& spec,
                              const std::function<void(const std::string&)>& say, const std::string& without) {
  try {
    return MakeReader<T>(p, spec);
  } catch (const DdsError& e) {
    say(std::string("cannot read ") + spec.name + " (" + e.what() + "): " + without + "; make the keystore again");
    return {};
  }
}
/// The same for a writer a node can do without (its loop statistics under an older keystore).
template <class T>
Writer<T> MakeWriterIfGranted(Participant& p, const topics::TopicSpec& spec,
                              const std::function<void(const std::string&)>& say, const std::string& without) {
  try {
    return MakeWriter<T>(p, spec);
  } catch (const DdsError& e) {
    say(std::string("cannot write ") + spec.name + " (" + e.what() + "): " + without + "; make the keystore again");
    return {};
  }
}

}  // namespace handshare::dds
