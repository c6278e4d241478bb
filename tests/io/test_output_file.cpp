// Outputs that never destroy what the user owns (gwnrt/io/output_file.h): an output that is an
// input under another name is refused, and a file is replaced only once written whole, through
// links and with its permissions; the mesh writer goes through it.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "gwnrt/io/mesh_writer.h"
#include "gwnrt/io/output_file.h"
#include "mesh_files.h"

namespace gwnrt {
namespace {

namespace fs = std::filesystem;

class OutputFile : public test::TempDirTest {
 protected:
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  static std::string read(const std::string& p) {
    std::ifstream f(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
  }
  // The folder's entries: a temporary file left behind would show here.
  size_t entries() const { return size_t(std::distance(fs::directory_iterator(dir_), fs::directory_iterator())); }
};

TEST_F(OutputFile, AnInputUnderAnotherNameIsRefused) {
  const std::string input = write("in.obj", "v 0 0 0\n"), other = write("other.obj", "v 1 1 1\n");
  fs::create_hard_link(input, path("hard.obj"));
  fs::create_symlink(input, path("soft.obj"));
  fs::create_directories(dir_ / "sub");
  for (const std::string& output :
       {input, path("hard.obj"), path("soft.obj"), (dir_ / "sub" / ".." / "in.obj").string()}) {
    SCOPED_TRACE(output);
    const Status s = check_output_is_not_input(output, {other, input});
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find(output), std::string::npos) << s.message();
    EXPECT_NE(s.message().find("the output is the input " + input), std::string::npos) << s.message();
  }
  EXPECT_TRUE(check_output_is_not_input(other, {input}).ok());
  EXPECT_TRUE(check_output_is_not_input(path("new.obj"), {input}).ok());  // not there yet
  EXPECT_TRUE(check_output_is_not_input(input, {path("missing.obj"), "-"}).ok());
  EXPECT_EQ(read(input), "v 0 0 0\n");
}

TEST_F(OutputFile, ReplacesOnlyOnceWrittenWhole) {
  const std::string target = write("out.txt", "old contents\n");
  ::chmod(target.c_str(), 0640);
  {
    ReplacingFile out(target);
    ASSERT_TRUE(out.open().ok());
    std::fputs("new", out.file());
    std::fflush(out.file());
    EXPECT_EQ(read(target), "old contents\n");  // written beside it until the commit
    EXPECT_EQ(entries(), 2u);
    ASSERT_TRUE(out.commit().ok());
  }
  EXPECT_EQ(read(target), "new");
  EXPECT_EQ(entries(), 1u);
  struct stat st;
  ASSERT_EQ(::stat(target.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0640u);
  // Never committed (an error or an exception on the way): the old file stays, nothing is left.
  {
    ReplacingFile out(target);
    ASSERT_TRUE(out.open().ok());
    std::fputs("partial", out.file());
  }
  EXPECT_EQ(read(target), "new");
  EXPECT_EQ(entries(), 1u);
  // A write the caller saw fail: reported by the destination's name, the old file kept.
  {
    ReplacingFile out(target);
    ASSERT_TRUE(out.open().ok());
    const Status s = out.commit(ENOSPC);
    EXPECT_EQ(s.code(), StatusCode::kIoError);
    EXPECT_NE(s.message().find(target + ": write failed"), std::string::npos) << s.message();
  }
  EXPECT_EQ(read(target), "new");
  EXPECT_EQ(entries(), 1u);
  // A new file, and a missing folder named in the refusal.
  {
    ReplacingFile out(path("fresh.txt"));
    ASSERT_TRUE(out.open().ok());
    std::fputs("fresh", out.file());
    ASSERT_TRUE(out.commit().ok());
  }
  EXPECT_EQ(read(path("fresh.txt")), "fresh");
  ReplacingFile nowhere(path("no_such_dir/x.txt"));
  const Status s = nowhere.open();
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find("no_such_dir/x.txt: cannot open for writing"), std::string::npos) << s.message();
}

TEST_F(OutputFile, ALinkIsFollowedAndKept) {
  const std::string target = write("real.txt", "old");
  fs::create_symlink(target, path("link.txt"));
  ReplacingFile out(path("link.txt"));
  ASSERT_TRUE(out.open().ok());
  std::fputs("through the link", out.file());
  ASSERT_TRUE(out.commit().ok());
  EXPECT_TRUE(fs::is_symlink(path("link.txt")));
  EXPECT_EQ(read(target), "through the link");
}

TEST_F(OutputFile, ADeviceIsWrittenInPlace) {
  if (!fs::exists("/dev/null") || !fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/null or /dev/full";
  ReplacingFile null("/dev/null");
  ASSERT_TRUE(null.open().ok());
  std::fputs("gone", null.file());
  EXPECT_TRUE(null.commit().ok());
  ReplacingFile full("/dev/full");
  ASSERT_TRUE(full.open().ok());
  std::fputs("no room", full.file());
  const Status s = full.commit();
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find("/dev/full: write failed"), std::string::npos) << s.message();
  EXPECT_TRUE(fs::exists("/dev/full"));
}

// The mesh writer through it: a refused mesh leaves the file that was there, a written one
// replaces it with nothing left beside it.
TEST_F(OutputFile, TheMeshWriterKeepsTheOldFileOnFailure) {
  const std::string target = write("mesh.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  SurfaceMesh bad;
  bad.positions = {vec3(0.0f), vec3(1.0f, 0.0f, 0.0f), vec3(0.0f, 1.0f, 0.0f)};
  bad.triangles = {uvec3(0, 1, 7)};  // an index out of range
  EXPECT_FALSE(write_surface_mesh(target, bad).ok());
  EXPECT_EQ(read(target), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  bad.triangles = {uvec3(0, 1, 2)};
  ASSERT_TRUE(write_surface_mesh(target, bad).ok());
  EXPECT_NE(read(target), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(entries(), 1u);
}

}  // namespace
}  // namespace gwnrt
