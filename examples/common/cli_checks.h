// CLI11 checks shared by the programs. CLI11's PositiveNumber and Range let nan through, and
// PositiveNumber words its refusal of 0 as "Value 0 not in range 0.000000 to 17976931348623157...",
// 300 digits (issue 15, item 16); these say what is wanted.
#pragma once

#include <charconv>
#include <cmath>
#include <string>
#include <system_error>

#include <CLI/CLI.hpp>

namespace gwnrt::examples {

// A number (the whole text) for which ok(v) holds; else "must be <wanted>, got '<text>'".
template <class Ok>
CLI::Validator number_check(Ok ok, const std::string& wanted, const std::string& name) {
  return CLI::Validator(
      [=](std::string& text) {
        double v = 0;
        const char* const end = text.data() + text.size();
        const auto r = std::from_chars(text.data(), end, v);
        if (r.ec != std::errc() || r.ptr != end || !ok(v)) return "must be " + wanted + ", got '" + text + "'";
        return std::string();
      },
      name);
}

inline CLI::Validator positive_number() {
  return number_check([](double v) { return std::isfinite(v) && v > 0; }, "a finite number > 0", "> 0");
}

// A share in [0, 1].
inline CLI::Validator unit_interval() {
  return number_check([](double v) { return v >= 0 && v <= 1; }, "a number in [0, 1]", "in [0, 1]");
}

}  // namespace gwnrt::examples
