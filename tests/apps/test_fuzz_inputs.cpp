// Every program as a subprocess on hostile input: the generated mutations of small valid mesh
// files (io/mesh_mutations.h), hostile rows of points and rays, and hostile argument lists.
// Nothing may crash, abort, hang or trip a sanitizer; a refusal is a non-zero exit with a message
// on stderr. Every input is made here from a fixed seed, so a failure reproduces: it prints the
// input's recipe or the program's arguments. Bounded to a few seconds per test in Release; CI
// also runs it under ASan + UBSan (scripts/check.sh sanitize), where a report fails it.
#include <cstdlib>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "cli_util.h"
#include "io/mesh_mutations.h"
#include "mesh_files.h"
#include "test_util.h"

namespace gwnrt {
namespace {

namespace fs = std::filesystem;
using test::quote;
using test::RunResult;

// ---------------------------------------------------------------------------------------------
// Programs as subprocesses.

// A run ended as a program should: by itself (no signal, no abort, not killed by the timeout),
// without a sanitizer report, and with a message on stderr when it failed.
void expect_clean_exit(const RunResult& r, const std::string& what) {
  EXPECT_TRUE(r.exited) << what << ": killed by a signal\n" << r.err.substr(0, 2000);
  if (!r.exited) return;
  EXPECT_NE(r.exit_code, 124) << what << ": timed out";
  // timeout(1) exits with 128 + the signal when its command was killed and it could not re-raise it.
  EXPECT_LT(r.exit_code, 124) << what << ": exit code " << r.exit_code << "\n" << r.err.substr(0, 2000);
  for (const char* report : {"Sanitizer", "runtime error", "terminate called", "Assertion"})
    EXPECT_EQ(r.err.find(report), std::string::npos) << what << ":\n" << r.err.substr(0, 4000);
  EXPECT_TRUE(r.exit_code == 0 || !r.err.empty()) << what << ": exit code " << r.exit_code << " but no message";
}

// Long enough for a sanitizer build on a busy machine; a hang is what it catches.
constexpr int kRunTimeoutSeconds = 60;

// Standard input is /dev/null unless given: a program reading "-" must not wait on the terminal.
RunResult run_with_timeout(const std::string& binary, const std::string& args,
                           const std::string& stdin_path = "/dev/null") {
  // timeout(1) re-raises a signal its command died of, so run_program still sees the signal.
  return test::run_program("timeout", "-k 5 " + std::to_string(kRunTimeoutSeconds) + " " + quote(binary) + " " + args,
                           stdin_path);
}

// Values an option may be given that a program must refuse or handle: empty, zero, negative,
// non-finite, beyond float, int, uint32 and uint64, denormal, malformed, binary, format strings,
// very long.
std::vector<std::string> hostile_values() {
  return {"",
          "0",
          "-1",
          "-0",
          "nan",
          "inf",
          "-inf",
          "1e400",
          "1e39",
          "3.5e38",
          "1e-45",
          "2147483648",
          "4294967296",
          "18446744073709551616",
          "-9223372036854775809",
          "0x10",
          "1,2",
          "abc",
          "\xff\xfe",
          "%s%n%x",
          std::string(5000, '7'),
          "--",
          "-"};
}

// The values option number `index` of a program is tried with: NaN and a negative, which every
// numeric check must refuse or carry, and `rotating` more of hostile_values(), a different few
// for each option, so that a program's options together meet most of them (each run costs a
// process start, so not every option meets every value).
std::vector<std::string> values_for(size_t index, size_t rotating) {
  const std::vector<std::string> all = hostile_values();
  std::vector<std::string> v = {"nan", "-1"};
  for (size_t k = 0; k < rotating; ++k) v.push_back(all[(index * rotating + k) % all.size()]);
  return v;
}

struct Option {
  Option(std::string n, std::vector<std::string> v = {}, std::string r = "")
      : name(std::move(n)), values(std::move(v)), replaces(std::move(r)) {}
  std::string name;
  std::vector<std::string> values;  // empty: values_for(its index, ProgramCase::rotating)
  std::string replaces;             // a base option it excludes (left out when it is tried)
};

struct ProgramCase {
  ProgramCase(std::string b, std::string p, std::vector<std::pair<std::string, std::string>> g)
      : binary(std::move(b)), positional(std::move(p)), given(std::move(g)) {}
  std::string binary;
  std::string positional;                                  // quoted
  std::vector<std::pair<std::string, std::string>> given;  // options of the base run, unquoted values
  std::vector<Option> options;                             // each tried with each of its values
  std::vector<std::string> extra;                          // whole argument lists to try as they are
  size_t rotating = 4;                                     // see values_for

  // The base run's arguments with `name` set to `value` (replaced where the base gives it: CLI11
  // refuses an option given twice, which would hide the value), without `left_out`.
  std::string args(const std::string& name = "", const std::string& value = "",
                   const std::string& left_out = "") const {
    std::string a = positional;
    bool replaced = false;
    for (const auto& [n, v] : given) {
      if (n == left_out) continue;
      const bool here = n == name;
      a += " " + n + " " + quote(here ? value : v);
      replaced = replaced || here;
    }
    if (!name.empty() && !replaced) a += " " + name + " " + quote(value);
    return a;
  }
};

// Runs the base, each option with each of its values, then the extra lists.
void run_program_case(const ProgramCase& c) {
  {
    const RunResult r = run_with_timeout(c.binary, c.args());
    expect_clean_exit(r, c.args());
    EXPECT_EQ(r.exit_code, 0) << "the base run must succeed: " << c.args() << "\n" << r.err;
  }
  for (size_t i = 0; i < c.options.size(); ++i) {
    const Option& o = c.options[i];
    for (const std::string& v : o.values.empty() ? values_for(i, c.rotating) : o.values) {
      const std::string args = c.args(o.name, v, o.replaces);
      expect_clean_exit(run_with_timeout(c.binary, args), args.substr(0, 300));
    }
  }
  for (const std::string& args : c.extra)
    expect_clean_exit(run_with_timeout(c.binary, args), args.empty() ? "(no arguments)" : args.substr(0, 300));
}

class FuzzCli : public FuzzDir {
 protected:
  void SetUp() override {
    FuzzDir::SetUp();
    if (std::system("timeout --version >/dev/null 2>&1") != 0) GTEST_SKIP() << "timeout(1) is not installed";
    mesh_ = write("tetra.obj", kTetraObj);
    open_mesh_ = write("small.obj", test::kSmallObj);
    points_ = write("points.txt", "0.2 0.2 0.2\n# a comment\n2 2 2\n");
    rays_ = write("rays.txt", "0.2 0.2 -1 0 0 1\n-1 0.25 0.25 1 0 0 0 inf\n");
    fs::create_directories(dir_ / "folder.obj");  // a name that is not a file
  }

  std::string out(const std::string& name) const { return (dir_ / name).string(); }

  // Hostile meshes: what is not a mesh file at all, and every `stride`-th generated mutation of
  // the small files. (/dev/zero as a mesh is read up to the line limit, a second: it has its
  // regression tests in io/test_read_file.cpp and test_query_cli.cpp.)
  std::vector<std::string> hostile_meshes(size_t stride) {
    std::vector<std::string> paths = {(dir_ / "folder.obj").string(), (dir_ / "missing.obj").string(),
                                      (dir_ / "no_extension").string()};
    const std::vector<Generated> generated = generate(1);
    for (size_t i = 0; i < generated.size(); i += stride)
      paths.push_back(write("mesh" + std::to_string(i) + generated[i].ext, generated[i].bytes));
    return paths;
  }

  // Hostile rows of numbers (points or rays): `valid` with a hostile number added or in place of
  // its first (every third of kHostileReals), garbage files, and what is not a file.
  std::vector<std::string> hostile_rows(const std::string& stem, const std::string& valid) {
    std::vector<std::string> texts = {"",
                                      "# only a comment\n",
                                      "\xEF\xBB\xBF" + valid,
                                      std::string(3u << 20, ' ') + "\n",  // past the 1 MiB line limit
                                      std::string(100, '\0'),
                                      "1 2\n",
                                      "1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18\n",
                                      valid + "\x01\x02\x03\n"};
    for (size_t k = 0; k < kHostileReals.size(); k += 3) {
      const std::string& v = kHostileReals[k];
      std::string t = valid;
      t.replace(t.find(' '), 0, " " + v);  // one number too many, and hostile
      texts.push_back(t);
      std::string u = valid;
      u.replace(0, u.find(' '), v);  // the first number replaced
      texts.push_back(u);
    }
    std::vector<std::string> paths = {"/dev/zero", "/dev/null", (dir_ / "folder.obj").string(),
                                      (dir_ / "missing.txt").string()};
    for (size_t i = 0; i < texts.size(); ++i) paths.push_back(write(stem + std::to_string(i) + ".txt", texts[i]));
    return paths;
  }

  std::string mesh_, open_mesh_, points_, rays_;
};

// Argument lists that are wrong as a whole: unknown options, missing values, stray positionals,
// and (where the program has no default run, which would be a whole benchmark) no arguments.
void add_shape_errors(ProgramCase& c, bool bare_run_is_a_benchmark = false) {
  const std::string base = c.args();
  if (!bare_run_is_a_benchmark) c.extra.push_back("");
  for (const std::string& a :
       {std::string("--help"), base + " --no-such-option=1", base + " stray positional", base + " --", base + " -",
        base + " --threads", base + " " + std::string(2000, '-'), base + " " + quote(std::string(100000, 'x'))})
    c.extra.push_back(a);
}

TEST_F(FuzzCli, Query) {
  const std::string b = test::program_binary("gwnrt-query");
  if (b.empty()) GTEST_SKIP() << "gwnrt-query is not built next to the tests";
  ProgramCase c{b, quote(mesh_), {{"--points", points_}}};
  c.options = {{"--points", hostile_rows("points", "0.2 0.3 0.4\n")},
               {"--fields", {"", ",", "w,,w", "all,sdf,proj,hbound", "W", std::string(3000, 'w')}},
               {"--level"},
               {"--newton-iterations"},
               {"--newton-tolerance"},
               {"--order"},
               {"--method", {"", "Taylor", "brute,crossing"}},
               {"--beta"},
               {"--device", {"", "cuda", "gpu"}},
               {"--threads"},
               {"-o", {"", "/proc/x.csv", out("no/such/dir/x.csv"), (dir_ / "folder.obj").string(), "/dev/full"}}};
  for (const std::string& m : hostile_meshes(6)) c.extra.push_back(quote(m) + " --points " + quote(points_));
  c.extra.push_back(quote(open_mesh_) + " --points " + quote(points_) + " --fields all,sdf,sdf1,proj,hbound");
  add_shape_errors(c);
  run_program_case(c);
  // Standard input that never ends a line, and one that is empty.
  expect_clean_exit(run_with_timeout(b, quote(mesh_) + " --points -", "/dev/zero"), "--points - < /dev/zero");
  expect_clean_exit(run_with_timeout(b, quote(mesh_) + " --points -"), "--points - < /dev/null");
}

TEST_F(FuzzCli, Trace) {
  const std::string b = test::program_binary("gwnrt-trace");
  if (b.empty()) GTEST_SKIP() << "gwnrt-trace is not built next to the tests";
  ProgramCase c{b, quote(mesh_), {{"--rays", rays_}}};
  std::vector<std::string> rays = hostile_rows("rays", "0 0 -5 0 0 1\n");
  for (const char* row : {"0 0 0 0 0 0\n", "0 0 0 1e-44 0 0\n", "0 0 0 3e38 3e38 3e38\n", "0 0 0 1 0 0 5 1\n",
                          "0 0 0 1 0 0 nan 1\n", "0 0 0 1 0 0 0 -inf\n", "1e39 0 0 1 0 0\n", "0 0 0 1 0 0 -inf inf\n"})
    rays.push_back(write("ray_row" + std::to_string(rays.size()) + ".txt", row));
  c.options = {{"--rays", rays}, {"--mode", {"", "GWN", "solid_angle"}},
               {"--level"},      {"--eps"},
               {"--max-steps"},  {"--max-crossings"},
               {"--beta"},       {"--device", {"", "cuda"}},
               {"--threads"},    {"-o", {"", "/proc/x.csv", out("no/such/dir/x.csv"), "/dev/full"}}};
  for (const std::string& m : hostile_meshes(11)) c.extra.push_back(quote(m) + " --rays " + quote(rays_));
  c.extra.push_back(quote(open_mesh_) + " --rays " + quote(rays_) + " --mode solid-angle");
  add_shape_errors(c);
  run_program_case(c);
  expect_clean_exit(run_with_timeout(b, quote(mesh_) + " --rays -", "/dev/zero"), "--rays - < /dev/zero");
}

TEST_F(FuzzCli, Mesh) {
  const std::string b = test::program_binary("gwnrt-mesh");
  if (b.empty()) GTEST_SKIP() << "gwnrt-mesh is not built next to the tests";
  ProgramCase c{b, quote(open_mesh_), {{"-o", out("out.ply")}, {"--resolution", "8"}}};
  c.options = {{"-o",
                {"", out("x.stl"), "/proc/x.ply", out("no/such/dir/x.ply"), (dir_ / "folder.obj").string(),
                 out("x.obj"), "/dev/full"}},
               {"--resolution"},
               {"--cell-size", {}, "--resolution"},
               {"--method", {"", "DC", "mc,dc"}},
               {"--level"},
               {"--smooth-angle"},
               {"--attributes", {"", ",", "uv,uv", "source,uv,color", "colour", std::string(1000, ',')}},
               {"--threads"},
               {"--device", {"", "cuda", "auto,cpu"}},
               // The report takes seconds (its distances to S), and only then is it written.
               {"--report-json", {out("no/such/dir/x.json")}}};
  for (const std::string& m : hostile_meshes(11))
    c.extra.push_back(quote(m) + " -o " + quote(out("out.ply")) + " --resolution 8");
  c.extra.push_back(c.args() + " --soup --report --attributes source,uv,color --method mc");
  add_shape_errors(c);
  run_program_case(c);
}

TEST_F(FuzzCli, Consistency) {
  const std::string b = test::program_binary("gwnrt-consistency");
  if (b.empty()) GTEST_SKIP() << "gwnrt-consistency is not built next to the tests";
  // Against the CPU itself: the whole comparison runs without a GPU.
  ProgramCase c{b,
                "--against cpu",
                {{"--mesh", open_mesh_},
                 {"--count", "64"},
                 {"--resolution", "8"},
                 {"--rays", rays_},
                 {"--image-width", "16"},
                 {"--image-height", "12"}}};
  c.options = {{"--mesh", hostile_meshes(4)},
               {"--points", hostile_rows("points", "0.2 0.3 0.4\n")},
               {"--rays", hostile_rows("rays", "0 0 -5 0 0 1\n")},
               {"--count"},
               {"--resolution"},
               {"--against", {"", "gpu", "cuda"}},
               {"--image-width"},
               {"--image-height"},
               {"--threads"},
               {"--json", {"", "/proc/x.json", out("no/such/dir/x.json"), "/dev/full"}}};
  add_shape_errors(c, true);
  run_program_case(c);
}

TEST_F(FuzzCli, SdfStudy) {
  const std::string b = test::program_binary("gwnrt-sdf-study");
  if (b.empty()) GTEST_SKIP() << "gwnrt-sdf-study is not built next to the tests";
  ProgramCase c{b,
                quote(open_mesh_),
                {{"--points", "64"},
                 {"--cloud", "64"},
                 {"--max-lines", "4096"},
                 {"--check-triangles", "4"},
                 {"--brute-points", "4"}}};
  c.options = {{"--points"},          {"--seed"},        {"--level"},     {"--beta"},
               {"--threads"},         {"--cloud"},       {"--max-lines"}, {"--smooth-share"},
               {"--check-triangles"}, {"--brute-points"}};
  // The closed tetrahedron has no smooth piece and no boundary.
  c.extra.push_back(quote(mesh_) + " --points 64 --cloud 64 --max-lines 64");
  for (const std::string& m : hostile_meshes(11))
    c.extra.push_back(quote(m) + " --points 64 --cloud 64 --max-lines 64");
  add_shape_errors(c, true);
  run_program_case(c);
}

// Every run that passes the checks takes a second (its timings are best of 3 runs of at least
// 0.1 s each, three times), so only values a check must refuse, and few meshes.
TEST_F(FuzzCli, BenchTrace) {
  const std::string b = test::program_binary("gwnrt-bench-trace");
  if (b.empty()) GTEST_SKIP() << "gwnrt-bench-trace is not built next to the tests";
  ProgramCase c{
      b,
      quote(open_mesh_),
      {{"--width", "8"}, {"--height", "6"}, {"--brute-rays", "4"}, {"--brute-seconds", "1"}, {"--check", "2"}}};
  c.rotating = 0;
  c.options = {{"--width", {"nan", "0", "-1", "2147483648", "1e9", ""}},
               {"--height", {"nan", "0", "4294967296"}},
               {"--brute-rays", {"nan", "-1", "18446744073709551616"}},
               {"--brute-seconds", {"nan", "0", "-inf"}},
               {"--threads"},
               {"--eps", {"nan", "0", "inf"}},
               {"--beta", {"nan", "0", "1e400"}},
               {"--level", {"nan", "inf", "abc"}},
               {"--check", {"-1", "1e3"}},
               {"--show", {"-1", "x"}}};
  for (const std::string& m : hostile_meshes(22)) c.extra.push_back(quote(m) + " --width 8 --height 6 --brute-rays 4");
  add_shape_errors(c, true);
  run_program_case(c);
}

TEST_F(FuzzCli, BenchQuery) {
  const std::string b = test::program_binary("gwnrt-bench-query");
  if (b.empty()) GTEST_SKIP() << "gwnrt-bench-query is not built next to the tests";
  ProgramCase c{b, quote(open_mesh_), {{"--points", "64"}, {"--brute-seconds", "0.05"}}};
  // A budget of 1e39 s made the brute-force subset's growth overflow its integer arithmetic.
  c.options = {{"--points"},
               {"--beta"},
               {"--brute-seconds", {"nan", "-1", "1e39", "inf"}},
               {"--threads"},
               {"--seed"},
               {"--only", {"", "no such mode"}},
               {"--baseline-json", {"", out("none.json"), "/dev/null", "/dev/zero", "/proc/self/status"}},
               {"--json", {"", "/proc/x.json", out("no/such/dir/x.json"), "/dev/full"}}};
  for (const std::string& m : hostile_meshes(11)) c.extra.push_back(quote(m) + " --points 64 --brute-seconds 0.05");
  add_shape_errors(c, true);
  run_program_case(c);
}

TEST_F(FuzzCli, BenchMesh) {
  const std::string b = test::program_binary("gwnrt-bench-mesh");
  if (b.empty()) GTEST_SKIP() << "gwnrt-bench-mesh is not built next to the tests";
  ProgramCase c{b, quote(open_mesh_) + " --no-self-intersections", {{"--resolutions", "8"}, {"--samples", "64"}}};
  c.options = {{"--resolutions", {"", "0", "8,,8", "8,0", "70000", "-8", "8,nan"}},
               {"--threads"},
               {"--samples"},
               {"--json", {"", "/proc/x.json", out("no/such/dir/x.json"), "/dev/full"}}};
  for (const std::string& m : hostile_meshes(11))
    c.extra.push_back(quote(m) + " --resolutions 8 --samples 64 --no-self-intersections");
  add_shape_errors(c, true);
  run_program_case(c);
}

// The library examples take a mesh path and nothing else. The Embree one exits with 2 when its
// one ray misses S (saying so on stdout): an answer, not an error.
TEST_F(FuzzCli, LibraryExamples) {
  for (const char* name : {"gwnrt-library-example", "gwnrt-engine-example", "gwnrt-embree-example"}) {
    const std::string b = test::program_binary(name);
    if (b.empty()) continue;  // the Embree one is built with Embree only
    std::vector<std::string> meshes = hostile_meshes(11);
    meshes.push_back(mesh_);
    for (const std::string& m : meshes) {
      RunResult r = run_with_timeout(b, quote(m));
      if (r.exited && r.exit_code == 2 && r.out.find("missed S") != std::string::npos) r.exit_code = 0;
      expect_clean_exit(r, name + (" " + m));
    }
  }
}

// gwnrt-render's options on a mesh (its scene files are fuzzed by the render tests). Every run
// costs most of a second (loading Embree and OpenImageIO), so only a few values a check must
// refuse, the bad output paths, and few meshes.
TEST_F(FuzzCli, Render) {
  const std::string b = test::program_binary("gwnrt-render");
  if (b.empty()) GTEST_SKIP() << "gwnrt-render is built with Embree only";
  ProgramCase c{b,
                quote(open_mesh_),
                {{"--width", "8"}, {"--height", "6"}, {"--spp", "1"}, {"--max-depth", "2"}, {"-o", out("out.png")}}};
  c.rotating = 0;
  c.options = {{"--width", {"2147483648"}}, {"--spp", {"-1"}},     {"-o", {"/dev/full"}},
               {"--fov", {"nan"}},          {"--level", {"1e39"}}, {"--stats-image", {out("no/such/dir/x.png")}}};
  c.extra.push_back(quote(write("bad.obj", "v 0 0 0\nf 1 2 3\n")) + " -o " + quote(out("out.png")));
  run_program_case(c);
}

// ---------------------------------------------------------------------------------------------
// Regression tests of limits once missing (input sizes, skipped lines), program by program
// (gwnrt-query's are in test_query_cli.cpp).

class LimitsCli : public FuzzCli {};

// Sizes from options are checked against the memory available before anything is allocated, and
// the refusal says what they would need. 10^6 x 10^6 rays ended in std::bad_alloc (an abort);
// --points 10^15 in a vector's allocation.
TEST_F(LimitsCli, SizesBeyondMemoryAreRefusedUpFront) {
  struct Case {
    const char* program;
    std::string args, says;
  };
  const std::vector<Case> cases = {
      {"gwnrt-bench-trace", quote(mesh_) + " --width 1000000 --height 1000000",
       "--width 1000000 --height 1000000: the arrays of 1000000000000 rays would need "},
      {"gwnrt-sdf-study", quote(mesh_) + " --points 1000000000000000",
       "--points 1000000000000000 --cloud 30000 would need "},
      {"gwnrt-sdf-study", quote(mesh_) + " --points 10 --cloud 1000000000000000",
       "--points 10 --cloud 1000000000000000 would need "},
      {"gwnrt-bench-query", quote(mesh_) + " --points 1000000000000000", "--points 1000000000000000 would need "}};
  for (const Case& c : cases) {
    const std::string b = test::program_binary(c.program);
    if (b.empty()) continue;
    const RunResult r = run_with_timeout(b, c.args);
    SCOPED_TRACE(std::string(c.program) + " " + c.args);
    expect_clean_exit(r, c.args);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find(std::string(c.program) + ": " + c.says), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(" of memory, more than the "), std::string::npos) << r.err;
  }
}

using test::kAddressSanitizer;

// gwnrt-mesh's budget is the memory available when that is less than the mesher's 8 GiB: under
// `ulimit -v` 1 GB, 1600 cells (1.7 GiB) are refused at once, saying so, where the mesher went on
// to allocate (and, without the limit, took 25 s and 2 GB).
TEST_F(LimitsCli, MeshingBudgetIsTheMemoryAvailable) {
  if (kAddressSanitizer) GTEST_SKIP() << "AddressSanitizer reserves more address space than ulimit -v allows";
  const std::string b = test::program_binary("gwnrt-mesh");
  if (b.empty()) GTEST_SKIP() << "gwnrt-mesh is not built next to the tests";
  const std::string script = "ulimit -v 1000000 && exec " + quote(b) + " " + quote(open_mesh_) + " -o " +
                             quote(out("o.ply")) + " --resolution 1600";
  const RunResult r = run_with_timeout("sh", "-c " + quote(script));
  expect_clean_exit(r, script);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("gwnrt-mesh: meshing at "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(the memory available now)"), std::string::npos) << r.err;
}

// A benchmark checks all its mesh files before it runs the first: a missing second one used to fail
// only after the first mesh's timings.
TEST_F(LimitsCli, BenchmarkInputFilesAreCheckedFirst) {
  const std::string b = test::program_binary("gwnrt-bench-trace");
  if (b.empty()) GTEST_SKIP() << "gwnrt-bench-trace is not built next to the tests";
  const RunResult r = run_with_timeout(b, quote(mesh_) + " " + quote(out("missing.obj")) + " --width 8 --height 6");
  expect_clean_exit(r, "two meshes, the second missing");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(out("missing.obj") + ": no such file"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("== "), std::string::npos) << "the first mesh ran:\n" << r.out;
}

// The tracer's options beyond what validate_trace_options takes (caps of 0, a NaN
// level, epsilon outside (0, 1), beta 0) used to fail with the library's message, which names no
// flag ("step and crossing caps must be at least 1"); gwnrt-render named --max-steps only. Both
// programs now refuse each such value while parsing, by the flag's name; the limits' edges and
// values whose float would be 0 or inf included. Values just inside are taken.
TEST_F(LimitsCli, TraceOptionsAreRefusedByTheirFlag) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> bad = {
      {"--max-crossings", {"0", "-1", "1.5", "nan", "4294967296"}},
      {"--max-steps", {"0", "-1", "2.5", "inf", "4294967296"}},
      {"--level", {"nan", "inf", "-inf", "1e39", "abc"}},
      {"--eps", {"0", "1", "-1e-5", "1e-50", "nan", "inf", "0.99999999"}},
      {"--beta", {"0", "-2", "nan", "inf", "1e39", "1e-50"}}};
  struct Program {
    const char* name;
    std::string args;  // a run that succeeds
  };
  const std::vector<Program> programs = {
      {"gwnrt-trace", quote(mesh_) + " --rays " + quote(rays_) + " -o " + quote(out("hits.csv"))},
      {"gwnrt-render", quote(open_mesh_) + " --integrator first-hit --width 8 --height 6 -o " + quote(out("f8.png"))}};
  size_t ran = 0;
  for (const Program& p : programs) {
    const std::string b = test::program_binary(p.name);
    if (b.empty()) continue;  // gwnrt-render is built with Embree only
    ++ran;
    for (const auto& [flag, values] : bad) {
      if (std::string(p.name) == "gwnrt-render" && flag == "--max-crossings") continue;  // not an option there
      for (const std::string& v : values) {
        const std::string args = p.args + " " + flag + " " + quote(v);
        SCOPED_TRACE(args);
        const RunResult r = run_with_timeout(b, args);
        expect_clean_exit(r, args);
        EXPECT_NE(r.exit_code, 0) << r.err;
        EXPECT_NE(r.err.find(flag + ": must be "), std::string::npos) << r.err;
      }
    }
    // The edges from inside: the smallest caps, epsilon near 1, a huge beta, a level out of reach
    // (a warning, not an error).
    std::string good = p.args + " --max-steps 1 --eps 0.999 --beta 1e30 --level -3e38";
    if (std::string(p.name) == "gwnrt-trace") good += " --max-crossings 1";
    const RunResult r = run_with_timeout(b, good);
    expect_clean_exit(r, good);
    EXPECT_EQ(r.exit_code, 0) << good << "\n" << r.err;
  }
  EXPECT_GE(ran, 1u) << "gwnrt-trace is not built next to the tests";
  // The benchmark takes the same three (its --eps had no upper limit, its --level no check).
  const std::string bench = test::program_binary("gwnrt-bench-trace");
  if (bench.empty()) return;
  for (const auto& [flag, values] : bad) {
    if (flag != "--level" && flag != "--eps" && flag != "--beta") continue;
    for (const std::string& v : values) {
      const std::string args = quote(mesh_) + " " + flag + " " + quote(v);
      SCOPED_TRACE(args);
      const RunResult r = run_with_timeout(bench, args);
      expect_clean_exit(r, args);
      EXPECT_NE(r.exit_code, 0) << r.err;
      EXPECT_NE(r.err.find(flag + ": must be "), std::string::npos) << r.err;
    }
  }
}

// Every program says what loading skipped (an OBJ line nobody knows), not just
// gwnrt-mesh and gwnrt-query, and still runs.
TEST_F(LimitsCli, UnknownObjStatementsAreWarnedAbout) {
  const std::string mesh = write("unknown.obj", std::string("vv 1 1 1\n") + kTetraObj);
  const std::vector<std::pair<const char*, std::string>> runs = {
      {"gwnrt-trace", quote(mesh) + " --rays " + quote(rays_)},
      {"gwnrt-mesh", quote(mesh) + " -o " + quote(out("o.ply")) + " --resolution 8"},
      {"gwnrt-sdf-study", quote(mesh) + " --points 64 --cloud 64 --max-lines 4096"},
      {"gwnrt-bench-trace", quote(mesh) + " --width 8 --height 6 --brute-rays 4 --check 0"},
      {"gwnrt-bench-query", quote(mesh) + " --points 64 --brute-seconds 0.05"},
      {"gwnrt-bench-mesh", quote(mesh) + " --resolutions 8 --samples 64 --no-self-intersections"}};
  for (const auto& [program, args] : runs) {
    const std::string b = test::program_binary(program);
    if (b.empty()) continue;
    const RunResult r = run_with_timeout(b, args);
    expect_clean_exit(r, args);
    EXPECT_EQ(r.exit_code, 0) << program << "\n" << r.err;
    EXPECT_NE(r.err.find(program + (": " + mesh +
                                    ": warning: 1 line with an unknown statement ignored (the first, line 1: 'vv')")),
              std::string::npos)
        << program << "\n"
        << r.err;
  }
}

}  // namespace
}  // namespace gwnrt
