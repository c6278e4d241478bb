// CLI11 checks shared by the programs. CLI11's PositiveNumber and Range let nan through, and
// PositiveNumber words its refusal of 0 as "Value 0 not in range 0.000000 to 17976931348623157...",
// 300 digits; these say what is wanted.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <system_error>

#include <CLI/CLI.hpp>

#include "gwnrt/base/option_limits.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/trace/trace_types.h"

namespace gwnrt::apps {

// Parses the command line: nothing when it was accepted, else the exit status, after CLI11 has
// said what it refused (or printed --help or --version, status 0). A refusal exits with `status`,
// not CLI11's own codes (101-115 by the kind of mistake), which no program documents and which
// differed from the status its own checks of the same input give.
inline std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv, int status = 1) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : status;
  }
  return std::nullopt;
}

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

// --weld-tolerance, in every program that reads a mesh (MeshLoadOptions::weld_tolerance).
inline void add_weld_tolerance_option(CLI::App& app, double& tolerance) {
  app.add_option("--weld-tolerance", tolerance,
                 "Also weld vertices closer than this fraction of the box's diagonal (files written with rounding; "
                 "default 0: only bit-identical positions)")
      ->check(number_check([](double v) { return v >= 0 && v <= kMaxWeldTolerance; }, "a number in [0, 0.01]",
                           "in [0, 0.01]"));
}

// --threads: a whole number in [1, kMaxThreads] (option_limits.h).
inline CLI::Validator thread_count() {
  const std::string range = "[1, " + std::to_string(kMaxThreads) + "]";
  return number_check([](double v) { return v >= 1 && v <= double(kMaxThreads) && v == std::floor(v); },
                      "a whole number in " + range, "in " + range);
}

inline CLI::Validator positive_number() {
  return number_check([](double v) { return std::isfinite(v) && v > 0; }, "a finite number > 0", "> 0");
}

// A share in [0, 1].
inline CLI::Validator unit_interval() {
  return number_check([](double v) { return v >= 0 && v <= 1; }, "a number in [0, 1]", "in [0, 1]");
}

// The tracer's options (gwnrt-trace, gwnrt-render --integrator first-hit), with the limits
// validate_trace_options enforces (trace_types.h), applied to the float each is stored in (1e-50
// is 0 as a float, 1e39 inf): the library's refusal names no flag, these name it (CLI11 puts the
// option's name before the message).
inline CLI::Validator trace_level_number() {
  // An angle in solid-angle mode is stored divided by 4 pi; refused here when its float is
  // infinite all the same (beyond 3.4e38 radians no angle means anything).
  return number_check([](double v) { return trace_level_valid(float(v)); }, "a finite number, not inf as a float",
                      "finite");
}
inline CLI::Validator trace_epsilon_number() {
  return number_check([](double v) { return trace_epsilon_valid(float(v)); },
                      "a number in (0, 1), not 0 or 1 as a float (a share of the mesh's box diagonal)", "in (0, 1)");
}
// Beta, the multipole accuracy scale (beta_valid, option_limits.h): the tracer's and the queries'.
inline CLI::Validator beta_number() {
  return number_check([](double v) { return beta_valid(float(v)); }, "a finite number >= 1, not inf as a float",
                      ">= 1");
}
// A step or crossing cap: a whole number the uint32_t it is stored in holds, at least 1.
inline CLI::Validator trace_cap_number() {
  return number_check(
      [](double v) { return v >= 0 && v <= double(UINT32_MAX) && v == std::floor(v) && trace_cap_valid(uint32_t(v)); },
      "a whole number in [1, " + std::to_string(UINT32_MAX) + "]", ">= 1");
}

}  // namespace gwnrt::apps
