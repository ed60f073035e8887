#include "sample_intake.hpp"

#include <cstdio>

#include "handshare/common/clock.hpp"
#include "handshare/dds/sample_checks.hpp"
#include "handshare/session/operator_command.hpp"
#include "handshare/session/visit_answers_message.hpp"
#include "server_conversions.hpp"

namespace handshare::server {

SampleIntake::SampleIntake(dds::Participant& participant, std::string session)
    : session_(std::move(session)),
      member_reader_(dds::MakeReader<msg::MemberInfo>(participant, dds::topics::kMemberInfo)),
      contact_reader_(dds::MakeReader<msg::ContactSet>(participant, dds::topics::kContactSet)),
      control_reader_(dds::MakeReader<msg::ControlEvent>(participant, dds::topics::kControlEvent)),
      visit_reader_(dds::MakeReader<msg::VisitAnswers>(participant, dds::topics::kVisitAnswers)),
      command_reader_(dds::MakeReader<msg::OperatorCommand>(participant, dds::topics::kOperatorCommand)),
      stats_reader_(dds::MakeReaderIfGranted<msg::LoopStatistics>(
          participant, dds::topics::kLoopStatistics,
          [](const std::string& line) { std::fprintf(stderr, "[world_server] %s\n", line.c_str()); },
          "the session log keeps no loop statistics")) {}

void SampleIntake::Take(TickInputs& in) {
  in.clear();
  TakeMembers(in);
  TakeControlEvents(in);
  TakeContactSets(in);
  TakeVisitAnswers(in);
  TakeOperatorCommands(in);
  TakeStations(in);
}

void SampleIntake::TakeMembers(TickInputs& in) {
  msg::MemberInfo info;
  dds::SampleMeta meta;
  while (member_reader_.TakeNext(info, meta)) {
    MemberInput m;
    m.instance = meta.instance;
    m.writer = meta.writer;
    if (meta.valid_data && info.leaving()) {
      m.kind = MemberInput::Kind::kLeaving;  // a clean leave, said in data
    } else if (meta.valid_data && meta.instance_state == dds::InstanceState::kAlive) {
      m.kind = MemberInput::Kind::kAnnounced;
      m.refused = dds::CheckMemberInfo(info, session_);
      m.member = ToMember(info);
    } else if (meta.instance_state != dds::InstanceState::kAlive) {
      m.kind = meta.instance_state == dds::InstanceState::kDisposed ? MemberInput::Kind::kDisposed
                                                                     : MemberInput::Kind::kNoWriters;
    } else {
      continue;  // no data, instance alive: nothing changed
    }
    in.members.push_back(std::move(m));
  }
  // Writers that vanished without disposing (killed processes, lost hosts), and writers back
  // after a partition healed.
  dds::WriterChange change;
  while (member_reader_.TakeWriterChange(change)) in.member_writers.push_back({change.writer, change.alive});
}

void SampleIntake::TakeControlEvents(TickInputs& in) {
  msg::ControlEvent sample;
  dds::SampleMeta meta;
  while (control_reader_.TakeNext(sample, meta)) {
    if (!meta.valid_data) continue;
    ControlEventInput e;
    e.user = sample.user().to_string();
    e.writer = meta.writer;
    e.refused = dds::CheckControlEvent(sample, session_);
    if (e.refused.empty()) {
      const auto input = ToControlInput(sample);
      if (!input) continue;  // CheckControlEvent refused every kind ToControlInput cannot map
      e.input = *input;
      e.record = ToControlRecord(sample, *input, common::UnixNowNs());
    }
    in.controls.push_back(std::move(e));
  }
}

void SampleIntake::TakeContactSets(TickInputs& in) {
  msg::ContactSet set;
  dds::SampleMeta meta;
  while (contact_reader_.TakeNext(set, meta)) {
    if (!meta.valid_data) continue;
    in.contacts.push_back({set, meta.writer, dds::CheckContactSet(set, session_)});
  }
}

void SampleIntake::TakeVisitAnswers(TickInputs& in) {
  msg::VisitAnswers sample;
  dds::SampleMeta meta;
  while (visit_reader_.TakeNext(sample, meta)) {
    if (!meta.valid_data) continue;
    VisitAnswersInput v;
    v.user = sample.user().to_string();
    v.writer = meta.writer;
    v.refused = dds::CheckVisitAnswers(sample, session_);
    if (v.refused.empty()) v.answers = session::FromMessage(sample);
    in.visits.push_back(std::move(v));
  }
}

void SampleIntake::TakeOperatorCommands(TickInputs& in) {
  msg::OperatorCommand sample;
  dds::SampleMeta meta;
  while (command_reader_.TakeNext(sample, meta)) {
    if (!meta.valid_data) continue;
    OperatorCommandInput c;
    c.user = sample.user().to_string();
    c.writer = meta.writer;
    c.refused = dds::CheckOperatorCommand(sample, session_);
    if (c.refused.empty()) {
      const auto command = session::FromMessage(sample);
      if (!command) continue;  // CheckOperatorCommand refused every kind FromMessage cannot map
      c.command = *command;
    }
    in.commands.push_back(std::move(c));
  }
}

void SampleIntake::TakeStations(TickInputs& in) {
  msg::LoopStatistics sample;
  dds::SampleMeta meta;
  while (stats_reader_ && stats_reader_.TakeNext(sample, meta)) {
    if (!meta.valid_data) continue;
    LoopStatisticsInput s;
    s.node = sample.node().to_string();
    s.refused = dds::CheckLoopStatistics(sample, session_);
    if (s.refused.empty()) s.loop = ToLoopRecord(sample, common::UnixNowNs());
    in.stations.push_back(std::move(s));
  }
}

}  // namespace handshare::server
