#include "handshare/audio_guide/guide.hpp"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>

#include "handshare/node/rejoin_clock.hpp"
#include "handshare/common/shutdown.hpp"
#include "handshare/dds/loop_traffic.hpp"
#include "handshare/dds/membership.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/dds/name_binding.hpp"
#include "handshare/dds/pass_statistics.hpp"
#include "handshare/dds/sample_checks.hpp"
#include "handshare/speech/audio_clip.hpp"
#include "handshare/speech/cues.hpp"
#include "handshare/speech/playback.hpp"
#include "handshare/speech/speech_synthesizer.hpp"

namespace handshare::audio_guide {

Guide::Guide(GuideConfig config) : config_(std::move(config)) {}

int Guide::Run() {
  using Clock = std::chrono::steady_clock;
  const std::string name = config_.name.empty() ? "audio-" + std::to_string(getpid()) : config_.name;
  if (!config_.out_dir.empty()) std::filesystem::create_directories(config_.out_dir);
  speech::SpeechSynthesizer synthesizer;  // fails early if eSpeak NG data is missing

  // Everything of the guide that lives on DDS; a rejoin makes a new one.
  const auto say = [&name](const std::string& line) {
    std::fprintf(stderr, "[audio_guide %s] %s\n", name.c_str(), line.c_str());
  };
  struct Link {
    Link(const common::SessionOptions& where, const std::string& name, bool cues,
         const std::function<void(const std::string&)>& say)
        : participant(where, "audio_guide/" + name),  // the role picks its identity
          member(participant, name, msg::NODE_AUDIO_GUIDE),
          board_reader(dds::MakeReader<msg::MessageBoard>(participant, dds::topics::kMessageBoard)),
          stats_writer(dds::MakeWriterIfGranted<msg::LoopStatistics>(
              participant, dds::topics::kLoopStatistics, say, "the operator's page shows no statistics of this guide")),
          stats_traffic(participant) {
      stats.node("audio_guide/" + name);
      stats.session(where.session);
      if (!cues) return;
      // A keystore made before the guide had cues grants neither: the guide speaks without them.
      scene_reader = dds::MakeReaderIfGranted<msg::SceneState>(participant, dds::topics::kSceneState, say,
                                                               "no world-change cue");
      control_reader = dds::MakeReaderIfGranted<msg::ControlState>(participant, dds::topics::kControlState, say,
                                                                   "no control cues");
    }
    dds::Participant participant;
    dds::MemberAnnouncement member;
    dds::Reader<msg::MessageBoard> board_reader;
    dds::Reader<msg::SceneState> scene_reader;
    dds::Reader<msg::ControlState> control_reader;
    dds::Writer<msg::LoopStatistics> stats_writer;  // empty: a keystore without the grant
    dds::LoopTraffic stats_traffic;
    msg::LoopStatistics stats;
  };
  auto link = std::make_unique<Link>(config_.where, name, config_.cues, say);
  node::RejoinClock rejoin(std::chrono::duration<double>(config_.rejoin_after_s));

  const auto start = Clock::now();
  std::uint32_t last_id = 0;
  bool heard = false;  // a board from the world server came since joining
  int spoken = 0;
  msg::MessageBoard board;
  dds::SampleMeta meta;
  dds::DroppedSamples dropped;
  speech::CueWatch cue_watch;
  int cues = 0;
  // A cue into its own WAV file with an output folder, else to the sound device.
  std::uint64_t playback_faults = 0;  // messages and cues the sound device did not play
  const auto sound = [&](speech::Cue cue, const std::string& why) {
    const speech::AudioClip clip = speech::SynthesizeCue(cue, synthesizer.sample_rate_hz());
    ++cues;
    if (!config_.out_dir.empty()) {
      const auto file = std::filesystem::path(config_.out_dir) /
                        ("cue_" + std::to_string(cues) + "_" + speech::CueName(cue) + ".wav");
      speech::WriteWav(file, clip.samples, clip.sample_rate_hz);
      std::printf("[audio_guide %s] cue #%d (%s: %s) -> %s\n", name.c_str(), cues, speech::CueName(cue), why.c_str(),
                  file.c_str());
    } else if (const speech::PlaybackStatus status = speech::Play(clip.samples, clip.sample_rate_hz, config_.alsa_device);
               !status.ok()) {
      ++playback_faults;
      std::fprintf(stderr, "[audio_guide %s] cannot play cue %s: %s\n", name.c_str(), speech::CueName(cue),
                   status.message.c_str());
    }
    std::fflush(stdout);
  };
  const auto sender = [](const dds::SampleMeta& m) { return "participant " + dds::ParticipantOf(m.writer); };
  // The board loop's statistics, once a second: its passes (each takes what arrived, or waits
  // up to 50 ms for a board: some 20 a second while quiet, one per message while it speaks), the
  // work of each (taking samples, speaking: synthesis and playback or the WAV written; not the
  // wait), failed playbacks as faults. The loop has no period: no jitter, no overruns.
  dds::PassStatistics passes(Clock::duration::max(), start);
  auto next_stats = start + std::chrono::seconds(1);
  Clock::time_point pass_began = start;
  Clock::duration waited{};
  bool in_pass = false;
  while (!common::ShutdownRequested()) {
    const auto pass_start = Clock::now();
    if (in_pass) passes.Record(pass_began, pass_began, pass_start - waited);
    in_pass = true;
    pass_began = pass_start;
    waited = {};
    if (pass_start >= next_stats) {
      passes.Fill(link->stats, pass_start);
      link->stats.faults(playback_faults);
      link->stats.samples_dropped(dropped.total());
      link->stats_traffic.Fill(link->stats, pass_start);
      if (link->stats_writer && link->stats_writer.matched_readers() > 0) link->stats_writer.Write(link->stats);
      next_stats = pass_start + std::chrono::seconds(1);
    }
    if (config_.where.duration.count() > 0 && Clock::now() - start >= config_.where.duration) break;
    msg::SceneState scene;
    while (link->scene_reader && link->scene_reader.TakeNext(scene, meta)) {
      if (!meta.valid_data ||
          !dropped.Accept("scene_state", sender(meta), dds::CheckSceneState(scene, config_.where.session), say)) {
        continue;
      }
      if (const auto cue = cue_watch.OnWorld(scene.scene().to_string())) sound(*cue, "world " + scene.scene().to_string());
    }
    msg::ControlState control;
    while (link->control_reader && link->control_reader.TakeNext(control, meta)) {
      if (!meta.valid_data ||
          !dropped.Accept("control_state", sender(meta), dds::CheckControlState(control, config_.where.session), say)) {
        continue;
      }
      const speech::ControlSnapshot now{control.scene().to_string(), control.index(), control.engaged(), control.changes()};
      if (const auto cue = cue_watch.OnControl(control.control_id().to_string(), now)) {
        sound(*cue, "control " + control.control_id().to_string());
      }
    }
    if (!link->board_reader.TakeNext(board, meta)) {
      if (rejoin.Due(heard)) {
        std::fprintf(stderr, "[audio_guide %s] %s\n", name.c_str(), rejoin.Message("board").c_str());
        const std::string joined =
            rejoin.Swap(link, [&] { return std::make_unique<Link>(config_.where, name, config_.cues, say); });
        std::fprintf(stderr, "[audio_guide %s] %s\n", name.c_str(), joined.c_str());
        continue;
      }
      const auto wait_start = Clock::now();
      link->board_reader.WaitForData(std::chrono::milliseconds(50));
      waited = Clock::now() - wait_start;
      continue;
    }
    if (!meta.valid_data) continue;
    const std::string bad = dds::CheckMessageBoard(board, config_.where.session);
    if (!dropped.Accept("message_board", "participant " + dds::ParticipantOf(meta.writer), bad, say)) continue;
    // The board comes in every language of the scene under one number: this guide speaks one.
    if (board.language().to_string() != config_.language || board.message_id() == last_id) continue;
    last_id = board.message_id();
    heard = true;
    // When it arrived, counted from joining (the reader exists): a late joiner's figure.
    std::printf("[audio_guide %s] message board #%u received %.3f s after joining\n", name.c_str(), last_id,
                std::chrono::duration<double>(Clock::now() - start).count());
    std::string text = board.text().to_string();
    if (board.next_action().size() > 0) text += " " + board.next_action().to_string();
    if (config_.language == "ja") text = board.reading().to_string();  // checked: kana, no kanji
    const speech::Utterance u = synthesizer.Synthesize(text, board.language().to_string());
    ++spoken;
    if (!config_.out_dir.empty()) {
      const auto base = std::filesystem::path(config_.out_dir) / ("message_" + std::to_string(last_id));
      speech::WriteWav(base.string() + ".wav", u.audio.samples, u.audio.sample_rate_hz);
      std::ofstream(base.string() + ".txt") << text << "\n";
      std::printf("[audio_guide %s] message #%u (%s, %.1f s) -> %s.wav\n", name.c_str(), last_id,
                  u.language.c_str(), u.audio.duration_s(), base.c_str());
    } else {
      const speech::PlaybackStatus status = speech::Play(u.audio.samples, u.audio.sample_rate_hz, config_.alsa_device);
      if (!status.ok()) {
        // No sound device is an expected condition on a headless box: say so, keep going.
        ++playback_faults;
        std::fprintf(stderr, "[audio_guide %s] cannot play message #%u: %s\n", name.c_str(), last_id,
                     status.message.c_str());
      } else {
        std::printf("[audio_guide %s] spoke message #%u (%s, %.1f s)\n", name.c_str(), last_id,
                    u.language.c_str(), u.audio.duration_s());
      }
    }
    std::fflush(stdout);
  }
  std::printf("[audio_guide %s] spoke %d messages, sounded %d cues\n", name.c_str(), spoken, cues);
  if (rejoin.rejoins() > 0) {
    std::printf("[audio_guide %s] rejoined the session %d time(s)\n", name.c_str(), rejoin.rejoins());
  }
  std::printf("[audio_guide %s] %s\n", name.c_str(), link->participant.TrafficSummary().c_str());
  return 0;
}

}  // namespace handshare::audio_guide
