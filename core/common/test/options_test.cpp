#include "handshare/common/options.hpp"

#include <gtest/gtest.h>

namespace handshare::common {
namespace {

Options Make() {
  Options o("prog", "test program");
  o.Value("domain", "D", "DDS domain", "0").Value("session", "S", "session", std::nullopt, true)
      .Flag("headless", "no window");
  return o;
}

TEST(Options, ParsesValuesFlagsAndDefaults) {
  Options o = Make();
  const char* argv[] = {"prog", "--session", "demo", "--headless", "--domain=7"};
  ASSERT_TRUE(o.Parse(5, argv));
  EXPECT_EQ(o.GetString("session"), "demo");
  EXPECT_TRUE(o.FlagSet("headless"));
  EXPECT_EQ(o.GetInt("domain", 0, 232), 7);
}

TEST(Options, RejectsUnknownMissingAndMalformed) {
  {
    Options o = Make();
    const char* argv[] = {"prog", "--session", "s", "--bogus"};
    EXPECT_THROW(o.Parse(4, argv), OptionError);
  }
  {
    Options o = Make();
    const char* argv[] = {"prog", "--domain", "3"};
    EXPECT_THROW(o.Parse(3, argv), OptionError);  // --session is required
  }
  {
    Options o = Make();
    const char* argv[] = {"prog", "--session"};
    EXPECT_THROW(o.Parse(2, argv), OptionError);  // value missing
  }
  {
    Options o = Make();
    const char* argv[] = {"prog", "--session", "s", "--domain", "12x"};
    ASSERT_TRUE(o.Parse(5, argv));
    EXPECT_THROW(o.GetInt("domain", 0, 232), OptionError);
  }
  {
    Options o = Make();
    const char* argv[] = {"prog", "--session", "s", "--domain", "500"};
    ASSERT_TRUE(o.Parse(5, argv));
    EXPECT_THROW(o.GetInt("domain", 0, 232), OptionError);  // out of range
  }
}

TEST(Options, ErrorNamesTheOption) {
  Options o = Make();
  const char* argv[] = {"prog", "--session", "s", "--domain", "abc"};
  ASSERT_TRUE(o.Parse(5, argv));
  try {
    o.GetInt("domain", 0, 232);
    FAIL() << "expected OptionError";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("--domain"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("abc"), std::string::npos);
  }
}

TEST(Options, AChoiceIsOneOfItsValuesOrNamesThem) {
  Options o("prog", "test program");
  o.Value("language", "en|ja", "language", "en");
  const char* argv[] = {"prog", "--language", "fr"};
  ASSERT_TRUE(o.Parse(3, argv));
  try {
    (void)o.GetChoice("language", {"en", "ja"});
    ADD_FAILURE() << "fr accepted";
  } catch (const OptionError& e) {
    EXPECT_STREQ(e.what(), "option --language: 'fr' is not one of en|ja");
  }
  Options d("prog", "test program");
  d.Value("language", "en|ja", "language", "en");
  const char* none[] = {"prog"};
  ASSERT_TRUE(d.Parse(1, none));
  EXPECT_EQ(d.GetChoice("language", {"en", "ja"}), "en");
}

TEST(Options, AVector3IsThreeBoundedNumbersOrTheErrorSaysSo) {
  for (const char* bad : {"1,2", "1,2,3,4", "1,2,x", "1,2,3x", "nan,0,0", "0,0,11", ""}) {
    Options o("prog", "test program");
    o.Value("origin", "X,Y,Z", "place", "0,0,0");
    const char* argv[] = {"prog", "--origin", bad};
    ASSERT_TRUE(o.Parse(3, argv));
    try {
      (void)o.GetVector3("origin", 10.0);
      ADD_FAILURE() << "'" << bad << "' accepted";
    } catch (const OptionError& e) {
      EXPECT_EQ(std::string(e.what()), std::string("option --origin: '") + bad + "' is not X,Y,Z (three numbers, each within 10)");
    }
  }
  Options o("prog", "test program");
  o.Value("origin", "X,Y,Z", "place", "0,0,0");
  const char* argv[] = {"prog", "--origin", "0.5,-1e-2,10"};
  ASSERT_TRUE(o.Parse(3, argv));
  EXPECT_EQ(o.GetVector3("origin", 10.0), (std::array<double, 3>{0.5, -0.01, 10.0}));
}

TEST(Options, HelpReturnsFalse) {
  Options o = Make();
  const char* argv[] = {"prog", "--help"};
  testing::internal::CaptureStdout();
  EXPECT_FALSE(o.Parse(2, argv));
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find("--session S"), std::string::npos);
}

}  // namespace
}  // namespace handshare::common
