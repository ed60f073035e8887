#pragma once
/// Command-line options for the node executables: declared up front so --help is generated,
/// and every mistake (unknown option, missing or malformed value) is an OptionError that
/// names the option, for main() to print with the usage and exit non-zero.
#include <map>
#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace handshare::common {

class OptionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Options {
 public:
  Options(std::string program, std::string summary);

  /// Declares --name VALUE. required: parsing fails without it.
  Options& Value(const std::string& name, const std::string& meta, const std::string& help,
                 std::optional<std::string> default_value = std::nullopt, bool required = false);
  /// Declares --name (no value).
  Options& Flag(const std::string& name, const std::string& help);

  /// Parses argv. Throws OptionError on a mistake. Returns false when --help was given
  /// (usage already printed to stdout): main() should exit 0.
  bool Parse(int argc, const char* const argv[]);

  std::string Usage() const;

  bool Has(const std::string& name) const;
  bool FlagSet(const std::string& name) const { return Has(name); }
  std::string GetString(const std::string& name) const;
  /// Integer in [min, max], else OptionError naming the option and the value.
  long GetInt(const std::string& name, long min, long max) const;
  /// Finite number in [min, max], else OptionError.
  double GetDouble(const std::string& name, double min, double max) const;
  /// "X,Y,Z", three finite numbers each within [-max_abs, max_abs], else OptionError.
  std::array<double, 3> GetVector3(const std::string& name, double max_abs) const;
  /// One of `choices`, else OptionError naming the option, the value and the choices.
  std::string GetChoice(const std::string& name, const std::vector<std::string>& choices) const;

 private:
  struct Spec {
    std::string meta, help;
    std::optional<std::string> default_value;
    bool takes_value = true;
    bool required = false;
  };
  const Spec& SpecOf(const std::string& name) const;

  std::string program_, summary_;
  std::vector<std::string> order_;
  std::map<std::string, Spec> specs_;
  std::map<std::string, std::string> values_;
};

}  // namespace handshare::common
