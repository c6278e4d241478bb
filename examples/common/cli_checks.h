// CLI11 checks shared by the programs. CLI11's PositiveNumber lets nan through and words its
// refusal of 0 as "Value 0 not in range 0.000000 to 17976931348623157...", 300 digits (issue 15,
// item 16); this one says what is wanted.
#pragma once

#include <charconv>
#include <cmath>
#include <string>
#include <system_error>

#include <CLI/CLI.hpp>

namespace gwnrt::examples {

inline CLI::Validator positive_number() {
  return CLI::Validator(
      [](std::string& text) {
        double v = 0;
        const char* const end = text.data() + text.size();
        const auto r = std::from_chars(text.data(), end, v);
        if (r.ec != std::errc() || r.ptr != end || !std::isfinite(v) || v <= 0)
          return "must be a finite number > 0, got '" + text + "'";
        return std::string();
      },
      "> 0");
}

// A share in [0, 1]; CLI11's Range(0.0, 1.0) let nan through.
inline CLI::Validator unit_interval() {
  return CLI::Validator(
      [](std::string& text) {
        double v = 0;
        const char* const end = text.data() + text.size();
        const auto r = std::from_chars(text.data(), end, v);
        if (r.ec != std::errc() || r.ptr != end || !(v >= 0 && v <= 1))
          return "must be a number in [0, 1], got '" + text + "'";
        return std::string();
      },
      "in [0, 1]");
}

}  // namespace gwnrt::examples
