#pragma once
/// The world server's readers: each tick takes the samples that arrived into TickInputs,
/// checked (dds/sample_checks.hpp: a refused sample carries why, and the session counts it)
/// and converted to the session's own types (server_conversions.hpp). Private to the server
/// library: the DDS side of the tick's inputs, as SessionPublisher is of its outputs.
#include <string>

#include "handshare/dds/messages.hpp"
#include "server_session.hpp"

namespace handshare::server {

class SampleIntake {
 public:
  SampleIntake(dds::Participant& participant, std::string session);

  /// Replaces `in` with what the readers hold now (member samples, then their writers' changes,
  /// control events, contact sets, questionnaires, operator commands).
  void Take(TickInputs& in);

 private:
  void TakeMembers(TickInputs& in);
  void TakeControlEvents(TickInputs& in);
  void TakeContactSets(TickInputs& in);
  void TakeVisitAnswers(TickInputs& in);
  void TakeOperatorCommands(TickInputs& in);
  void TakeStations(TickInputs& in);

  std::string session_;
  dds::Reader<msg::MemberInfo> member_reader_;
  dds::Reader<msg::ContactSet> contact_reader_;
  dds::Reader<msg::ControlEvent> control_reader_;
  dds::Reader<msg::VisitAnswers> visit_reader_;
  dds::Reader<msg::OperatorCommand> command_reader_;
  dds::Reader<msg::LoopStatistics> stats_reader_;
};

}  // namespace handshare::server
