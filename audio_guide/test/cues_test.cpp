#include "handshare/speech/cues.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

namespace handshare::speech {
namespace {

constexpr int kRate = 22050;

double Rms(const AudioClip& c, double from_s, double to_s) {
  const auto a = static_cast<std::size_t>(from_s * c.sample_rate_hz);
  const auto b = std::min(c.samples.size(), static_cast<std::size_t>(to_s * c.sample_rate_hz));
  double sum = 0.0;
  for (std::size_t i = a; i < b; ++i) sum += static_cast<double>(c.samples[i]) * c.samples[i];
  return b > a ? std::sqrt(sum / static_cast<double>(b - a)) : 0.0;
}

// The dominant frequency from upward zero crossings over [from_s, to_s).
double CrossingHz(const AudioClip& c, double from_s, double to_s) {
  const auto a = static_cast<std::size_t>(from_s * c.sample_rate_hz);
  const auto b = static_cast<std::size_t>(to_s * c.sample_rate_hz);
  int crossings = 0;
  for (std::size_t i = a + 1; i < b; ++i) crossings += (c.samples[i - 1] < 0 && c.samples[i] >= 0) ? 1 : 0;
  return crossings / (to_s - from_s);
}

int Peak(const AudioClip& c) {
  int peak = 0;
  for (const auto s : c.samples) peak = std::max(peak, std::abs(static_cast<int>(s)));
  return peak;
}

TEST(Cues, EachCueHasItsLengthLoudnessAndShape) {
  for (const Cue cue : {Cue::kButtonClick, Cue::kLeverDetent, Cue::kPageTurn, Cue::kWorldChange}) {
    const AudioClip c = SynthesizeCue(cue, kRate);
    EXPECT_EQ(c.sample_rate_hz, kRate);
    EXPECT_GT(Peak(c), 2000) << CueName(cue);
    EXPECT_LE(Peak(c), 8200) << CueName(cue) << ": a cue stays well below the speech";
  }
  const AudioClip click = SynthesizeCue(Cue::kButtonClick, kRate);
  EXPECT_NEAR(click.duration_s(), 0.040, 1e-3);
  EXPECT_GT(Rms(click, 0.0, 0.010), 20.0 * Rms(click, 0.020, 0.040)) << "a click is over in 10 ms";
  EXPECT_NEAR(CrossingHz(click, 0.002, 0.012), 2500.0, 300.0);

  const AudioClip detent = SynthesizeCue(Cue::kLeverDetent, kRate);
  EXPECT_NEAR(detent.duration_s(), 0.100, 1e-3);
  EXPECT_GT(Rms(detent, 0.060, 0.070), 10.0 * Rms(detent, 0.040, 0.058)) << "the second tick";

  const AudioClip page = SynthesizeCue(Cue::kPageTurn, kRate);
  EXPECT_NEAR(page.duration_s(), 0.250, 1e-3);
  EXPECT_GT(Rms(page, 0.100, 0.150), 3.0 * Rms(page, 0.0, 0.020)) << "a swish swells and fades";
  EXPECT_GT(Rms(page, 0.100, 0.150), 3.0 * Rms(page, 0.230, 0.250));

  const AudioClip world = SynthesizeCue(Cue::kWorldChange, kRate);
  EXPECT_NEAR(world.duration_s(), 0.600, 1e-3);
  EXPECT_NEAR(CrossingHz(world, 0.010, 0.140), 660.0, 30.0);
  EXPECT_GT(Rms(world, 0.400, 0.600), 0.0) << "the chime rings on";

  EXPECT_THROW((void)SynthesizeCue(Cue::kButtonClick, 100), std::invalid_argument);
}

TEST(Cues, ControlStatesSoundAsTheControlMoves) {
  CueWatch w;
  EXPECT_EQ(w.OnWorld("solar_system"), std::nullopt) << "the first world is not a change";
  // First seen: silent, whatever the state.
  EXPECT_EQ(w.OnControl("lever", {"solar_system", 0, false, 0}), std::nullopt);
  EXPECT_EQ(w.OnControl("button", {"solar_system", -1, false, 0}), std::nullopt);
  EXPECT_EQ(w.OnControl("book", {"solar_system", -1, false, 0}), std::nullopt);
  // A lever to another detent, and back.
  EXPECT_EQ(w.OnControl("lever", {"solar_system", 1, false, 1}), Cue::kLeverDetent);
  EXPECT_EQ(w.OnControl("lever", {"solar_system", 1, false, 1}), std::nullopt) << "the same state again";
  EXPECT_EQ(w.OnControl("lever", {"solar_system", 0, false, 2}), Cue::kLeverDetent);
  // A button pressed clicks; released is silent.
  EXPECT_EQ(w.OnControl("button", {"solar_system", -1, true, 1}), Cue::kButtonClick);
  EXPECT_EQ(w.OnControl("button", {"solar_system", -1, false, 2}), std::nullopt);
  // A book opened, turned to page 2, closed.
  EXPECT_EQ(w.OnControl("book", {"solar_system", 0, true, 1}), Cue::kPageTurn);
  EXPECT_EQ(w.OnControl("book", {"solar_system", 2, true, 2}), Cue::kPageTurn);
  EXPECT_EQ(w.OnControl("book", {"solar_system", -1, false, 3}), std::nullopt);
  // A new revision of the same world is silent; another world chimes and forgets the controls,
  // so a lever of the new world, at detent 0 again, makes no sound.
  EXPECT_EQ(w.OnWorld("solar_system"), std::nullopt);
  EXPECT_EQ(w.OnWorld("dinosaur"), Cue::kWorldChange);
  EXPECT_EQ(w.OnControl("lever", {"solar_system", 0, false, 0}), std::nullopt);
  // A control state of another world than the one last seen for that id is a first sight.
  EXPECT_EQ(w.OnControl("lever", {"start_menu", 1, false, 5}), std::nullopt);
}

// Across a network a world's control states can arrive before the world's scene state: the
// control is still known when it moves (net.tour lost the lever's detent this way).
TEST(Cues, AControlSeenBeforeItsWorldStillSoundsWhenItMoves) {
  CueWatch w;
  EXPECT_EQ(w.OnWorld("start_menu"), std::nullopt);
  EXPECT_EQ(w.OnControl("lever", {"solar_system", 0, false, 0}), std::nullopt);  // ahead of its world
  EXPECT_EQ(w.OnWorld("solar_system"), Cue::kWorldChange);
  EXPECT_EQ(w.OnControl("lever", {"solar_system", 1, false, 1}), Cue::kLeverDetent);
  // Leaving and coming back: the old world's controls were forgotten, its first state is silent.
  EXPECT_EQ(w.OnWorld("dinosaur"), Cue::kWorldChange);
  EXPECT_EQ(w.OnWorld("solar_system"), Cue::kWorldChange);
  EXPECT_EQ(w.OnControl("lever", {"solar_system", 0, false, 0}), std::nullopt);
}

}  // namespace
}  // namespace handshare::speech
