// Running one of gwnrt's programs as a subprocess, for the CLI tests.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gwnrt/io/mesh_io.h"
#include "gwnrt/model/model.h"

namespace gwnrt::test {

namespace fs = std::filesystem;

// The program `name` as built beside the tests (GWNRT_PROGRAM_DIR, <build>/bin); empty when it is
// not there (a build without the programs).
inline std::string program_binary(const std::string& name) {
  std::error_code ec;
  const fs::path candidate = fs::path(GWNRT_PROGRAM_DIR) / name;
  return fs::exists(candidate, ec) ? candidate.string() : std::string();
}

inline std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

inline std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline std::string temp_path(const std::string& stem) {
  static int counter = 0;
  return ::testing::TempDir() + "gwnrt_cli_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + "_" +
         stem;
}

struct RunResult {
  bool exited = false;  // false: killed by a signal
  int exit_code = -1;
  std::string out, err;
};

inline RunResult run_program(const std::string& binary, const std::string& args, const std::string& stdin_path = "") {
  const std::string out = temp_path("out.txt"), err = temp_path("err.txt");
  // exec, so that a crash shows up as a signal in the status rather than as the shell's exit code.
  std::string cmd = "exec " + quote(binary) + " " + args + " >" + quote(out) + " 2>" + quote(err);
  if (!stdin_path.empty()) cmd += " <" + quote(stdin_path);
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.exited = status != -1 && WIFEXITED(status);
  if (r.exited) r.exit_code = WEXITSTATUS(status);
  r.out = read_file(out);
  r.err = read_file(err);
  std::remove(out.c_str());
  std::remove(err.c_str());
  return r;
}

// A georeferenced site's offset for the tests of far-off input: UTM easting and northing in
// metres, where float steps by 0.25.
constexpr double kUtm[3] = {512345.678, 4123456.789, 123.25};

// The unit tetrahedron (corner at 0, faces x = 0, y = 0, z = 0 and the slanted one) moved by kUtm,
// written to `path` as OBJ with 17 significant digits: a mesh GwnModel::build refuses where it lies
// (its box is 4e-7 of its largest coordinate), which the test checks.
inline void write_far_tetrahedron(const std::string& path) {
  {
    std::ofstream m(path);
    m << std::setprecision(17);
    for (const dvec3& v : {dvec3(0, 0, 0), dvec3(1, 0, 0), dvec3(0, 1, 0), dvec3(0, 0, 1)})
      m << "v " << v.x + kUtm[0] << " " << v.y + kUtm[1] << " " << v.z + kUtm[2] << "\n";
    m << "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  }
  Mesh as_is;
  ASSERT_TRUE(load_mesh(path, as_is).ok());
  GwnModel refused;
  const Status s = GwnModel::build(std::move(as_is), refused);
  EXPECT_NE(s.message().find("translate the mesh near the origin"), std::string::npos) << s.message();
}

// The cells of a CSV text, by row (the header first).
inline std::vector<std::vector<std::string>> csv_rows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream ls(line);
    while (std::getline(ls, cell, ',')) cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

// A cell or token in double ("inf" and "nan" included); fails the test when it is not a number.
inline double cell_double(const std::string& c) {
  char* end = nullptr;
  const double v = std::strtod(c.c_str(), &end);
  EXPECT_TRUE(!c.empty() && *end == '\0') << "bad number '" << c << "'";
  return v;
}

// A position column of a recentred program (gwnrt-query, gwnrt-trace): `text` is written in the
// input's coordinates, about `origin` (MeshLoadReport::origin), for the model's float `v`. Read
// back as the programs read a position (in double, origin subtracted, rounded to float) it is v
// to the bit, unless v holds bits finer than a double's step at origin + v (|v| below about
// 2^-29 |origin|): then it is v to that step.
inline void expect_position_reads_back(const std::string& text, double origin, float v) {
  const double back = cell_double(text) - origin;
  if (float(back) == v) return;
  const double x = origin + double(v);
  EXPECT_LE(std::fabs(back - double(v)), std::nextafter(std::fabs(x), HUGE_VAL) - std::fabs(x))
      << "'" << text << "' - " << origin << " is not " << v;
  EXPECT_NE(float(x - origin), v) << "'" << text << "' - " << origin << " does not read back to " << v
                                  << " while the double origin + v does";
}

// A copy of `from` moved by `t`, for the tests of far-off (georeferenced) input: in an OBJ mesh
// (`obj`) each `v` line's position, in a points or rays file each row's first three numbers (the
// point, the ray's origin), written with 17 significant digits (each reads back as the double
// sum). Other lines and numbers are copied as they are; comments are dropped from rows.
inline void write_translated(const std::string& from, const std::string& to, const double (&t)[3], bool obj) {
  std::ifstream in(from);
  std::ofstream out(to);
  std::string line;
  char buf[32];
  while (std::getline(in, line)) {
    std::string body = line;
    if (obj) {
      if (line.rfind("v ", 0) != 0) {
        out << line << "\n";
        continue;
      }
      body = line.substr(2);
      out << "v";
    } else {
      body = line.substr(0, line.find('#'));
    }
    std::istringstream ls(body);
    std::string token;
    for (int k = 0; ls >> token; ++k) {
      if (k < 3) {
        std::snprintf(buf, sizeof buf, "%.17g", cell_double(token) + t[k]);
        token = buf;
      }
      out << (k || obj ? " " : "") << token;
    }
    out << "\n";
  }
}

}  // namespace gwnrt::test
