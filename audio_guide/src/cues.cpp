#include "handshare/speech/cues.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

namespace handshare::speech {

namespace {

constexpr double kPeak = 0.25 * 32767.0;

std::int16_t ToSample(double v) { return static_cast<std::int16_t>(std::lround(std::clamp(v, -1.0, 1.0) * kPeak)); }

// A decaying sine tick at f_Hz starting at t0_s, amplitude a, time constant tau_s.
void AddTick(std::vector<double>& out, int rate, double t0_s, double f_Hz, double a, double tau_s) {
  const auto begin = static_cast<std::size_t>(t0_s * rate);
  for (std::size_t i = begin; i < out.size(); ++i) {
    const double t = static_cast<double>(i - begin) / rate;
    out[i] += a * std::exp(-t / tau_s) * std::sin(2.0 * std::numbers::pi * f_Hz * t);
  }
}

}  // namespace

const char* CueName(Cue cue) noexcept {
  switch (cue) {
    case Cue::kButtonClick: return "click";
    case Cue::kLeverDetent: return "detent";
    case Cue::kPageTurn: return "page";
    case Cue::kWorldChange: return "world";
  }
  return "cue";
}

AudioClip SynthesizeCue(Cue cue, int sample_rate_hz) {
  if (sample_rate_hz < 8000 || sample_rate_hz > 192000) {
    throw std::invalid_argument("SynthesizeCue: sample rate " + std::to_string(sample_rate_hz) +
                                " Hz outside 8000..192000");
  }
  const int rate = sample_rate_hz;
  const auto length = [&](double s) { return static_cast<std::size_t>(s * rate); };
  std::vector<double> v;
  std::mt19937 rng(7);  // the same cue every time
  std::normal_distribution<double> noise(0.0, 1.0);
  switch (cue) {
    case Cue::kButtonClick: {
      v.assign(length(0.040), 0.0);
      AddTick(v, rate, 0.0, 2500.0, 0.8, 0.003);
      for (std::size_t i = 0; i < length(0.002) && i < v.size(); ++i) v[i] += 0.4 * noise(rng);  // the transient
      break;
    }
    case Cue::kLeverDetent: {
      v.assign(length(0.100), 0.0);
      AddTick(v, rate, 0.0, 1200.0, 0.5, 0.004);
      AddTick(v, rate, 0.060, 1200.0, 0.4, 0.004);
      break;
    }
    case Cue::kPageTurn: {
      v.assign(length(0.250), 0.0);
      // Noise, smoothed by a one-pole low-pass (a soft swish, not hiss), under a sine envelope.
      double low = 0.0;
      for (std::size_t i = 0; i < v.size(); ++i) {
        low += 0.3 * (noise(rng) - low);
        v[i] = 0.9 * std::sin(std::numbers::pi * static_cast<double>(i) / static_cast<double>(v.size())) * low;
      }
      break;
    }
    case Cue::kWorldChange: {
      v.assign(length(0.600), 0.0);
      AddTick(v, rate, 0.0, 660.0, 0.6, 0.12);
      AddTick(v, rate, 0.150, 880.0, 0.6, 0.15);
      break;
    }
  }
  AudioClip clip;
  clip.sample_rate_hz = rate;
  clip.samples.reserve(v.size());
  for (const double x : v) clip.samples.push_back(ToSample(x));
  return clip;
}

std::optional<Cue> CueWatch::OnControl(const std::string& control_id, const ControlSnapshot& now) {
  const auto it = controls_.find(control_id);
  std::optional<ControlSnapshot> before;
  if (it != controls_.end() && it->second.scene == now.scene) before = it->second;
  controls_[control_id] = now;
  if (!before || before->changes == now.changes) return std::nullopt;
  if (now.engaged && now.index >= 0) {  // a book, open
    if (!before->engaged || before->index != now.index) return Cue::kPageTurn;
    return std::nullopt;
  }
  if (now.index < 0) {  // a button or an arrow (or a book closing: silent)
    if (now.engaged && !before->engaged) return Cue::kButtonClick;
    return std::nullopt;
  }
  if (!now.engaged && before->index != now.index && !before->engaged) return Cue::kLeverDetent;  // a lever
  return std::nullopt;
}

std::optional<Cue> CueWatch::OnWorld(const std::string& scene) {
  if (scene == world_) return std::nullopt;
  const bool first = world_.empty();
  world_ = scene;
  // The controls of other worlds are forgotten (a world visited again starts its controls
  // afresh); those of this world stay: across a network its controls' states may arrive before
  // its scene state (seen: the lever's first state, then the world, then the lever's detent).
  std::erase_if(controls_, [&](const auto& entry) { return entry.second.scene != scene; });
  if (first) return std::nullopt;
  return Cue::kWorldChange;
}

}  // namespace handshare::speech
