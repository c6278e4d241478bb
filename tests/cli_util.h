// Running a command-line program of the examples as a subprocess, for the CLI tests.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace gwnrt::test {

namespace fs = std::filesystem;

// The test target does not know where the examples are built, so find the program next to the
// test binary's own build directory; empty when it is not there (a build without examples).
inline std::string example_binary(const std::string& name) {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  const fs::path candidate = self.parent_path() / ".." / "examples" / name;
  return fs::exists(candidate, ec) ? fs::canonical(candidate, ec).string() : std::string();
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

}  // namespace gwnrt::test
