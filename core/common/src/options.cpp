#include "handshare/common/options.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <sstream>

namespace handshare::common {

Options::Options(std::string program, std::string summary)
    : program_(std::move(program)), summary_(std::move(summary)) {
  Flag("help", "print this help and exit");
}

Options& Options::Value(const std::string& name, const std::string& meta, const std::string& help,
                        std::optional<std::string> default_value, bool required) {
  order_.push_back(name);
  specs_[name] = Spec{meta, help, std::move(default_value), true, required};
  return *this;
}

Options& Options::Flag(const std::string& name, const std::string& help) {
  order_.push_back(name);
  specs_[name] = Spec{"", help, std::nullopt, false, false};
  return *this;
}

std::string Options::Usage() const {
  std::ostringstream out;
  out << "usage: " << program_;
  for (const auto& name : order_) {
    const Spec& s = specs_.at(name);
    if (name == "help") continue;
    const std::string text = "--" + name + (s.takes_value ? " " + s.meta : "");
    out << (s.required ? " " + text : " [" + text + "]");
  }
  out << "\n\n" << summary_ << "\n\noptions:\n";
  for (const auto& name : order_) {
    const Spec& s = specs_.at(name);
    std::string text = "  --" + name + (s.takes_value ? " " + s.meta : "");
    if (text.size() < 28) text.resize(28, ' ');
    out << text << " " << s.help;
    if (s.default_value) out << " (default: " << *s.default_value << ")";
    if (s.required) out << " (required)";
    out << "\n";
  }
  return out.str();
}

bool Options::Parse(int argc, const char* const argv[]) {
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg.rfind("--", 0) != 0 || arg.size() == 2) {
      throw OptionError("unexpected argument '" + arg + "' (options start with --)");
    }
    std::string name = arg.substr(2);
    std::optional<std::string> inline_value;
    if (const auto eq = name.find('='); eq != std::string::npos) {
      inline_value = name.substr(eq + 1);
      name = name.substr(0, eq);
    }
    const auto it = specs_.find(name);
    if (it == specs_.end()) throw OptionError("unknown option --" + name);
    if (name == "help") {
      std::cout << Usage();
      return false;
    }
    if (!it->second.takes_value) {
      if (inline_value) throw OptionError("option --" + name + " takes no value");
      values_[name] = "1";
      continue;
    }
    if (inline_value) {
      values_[name] = *inline_value;
    } else {
      if (i + 1 >= argc) throw OptionError("option --" + name + " needs a value " + it->second.meta);
      values_[name] = argv[++i];
    }
  }
  for (const auto& [name, spec] : specs_) {
    if (spec.required && !values_.count(name)) throw OptionError("missing required option --" + name);
  }
  return true;
}

const Options::Spec& Options::SpecOf(const std::string& name) const {
  const auto it = specs_.find(name);
  if (it == specs_.end()) throw std::logic_error("option --" + name + " was never declared");
  return it->second;
}

bool Options::Has(const std::string& name) const {
  SpecOf(name);
  return values_.count(name) > 0;
}

std::string Options::GetString(const std::string& name) const {
  const Spec& spec = SpecOf(name);
  if (const auto it = values_.find(name); it != values_.end()) return it->second;
  if (spec.default_value) return *spec.default_value;
  throw OptionError("option --" + name + " was not given");
}

long Options::GetInt(const std::string& name, long min, long max) const {
  const std::string text = GetString(name);
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno == ERANGE || v < min || v > max) {
    throw OptionError("option --" + name + ": '" + text + "' is not an integer in [" +
                      std::to_string(min) + ", " + std::to_string(max) + "]");
  }
  return v;
}

double Options::GetDouble(const std::string& name, double min, double max) const {
  const std::string text = GetString(name);
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v) || v < min || v > max) {
    std::ostringstream range;
    range << "[" << min << ", " << max << "]";
    throw OptionError("option --" + name + ": '" + text + "' is not a number in " + range.str());
  }
  return v;
}

std::array<double, 3> Options::GetVector3(const std::string& name, double max_abs) const {
  const std::string text = GetString(name);
  std::array<double, 3> v{};
  char tail = 0;
  const bool parsed = std::sscanf(text.c_str(), "%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &tail) == 3;
  if (!parsed || !std::isfinite(v[0] + v[1] + v[2]) ||
      std::max({std::abs(v[0]), std::abs(v[1]), std::abs(v[2])}) > max_abs) {
    std::ostringstream range;
    range << max_abs;
    throw OptionError("option --" + name + ": '" + text + "' is not X,Y,Z (three numbers, each within " + range.str() + ")");
  }
  return v;
}

std::string Options::GetChoice(const std::string& name, const std::vector<std::string>& choices) const {
  std::string text = GetString(name);
  for (const std::string& c : choices) {
    if (c == text) return text;
  }
  std::string list;
  for (const std::string& c : choices) list += (list.empty() ? "" : "|") + c;
  throw OptionError("option --" + name + ": '" + text + "' is not one of " + list);
}

}  // namespace handshare::common
