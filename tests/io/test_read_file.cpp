// Reading a file within limits (read_file.h): streams that never end or are not text stop at
// their first control byte, a line longer than the limit is refused in text but not in a binary
// body (the PLY reader's too), and the total size is capped before or while reading.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "gwnrt/io/mesh_io.h"
#include "gwnrt/io/read_file.h"
#include "io_fixtures.h"

namespace gwnrt {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------
// Reading within limits: a stream that never ends, a file beyond memory.

// /dev/zero under a mesh file's name grew the read buffer until memory ran out, and then stopped
// at the line limit; /dev/urandom (newlines often enough) was read to the end of memory. Both
// now stop at their first control byte, naming the file and the line. The PLY header is text too.
TEST_F(TempFiles, StreamsThatAreNotTextStopAtTheirFirstBytes) {
  for (const char* name : {"zero.obj", "zero.ply", "random.obj", "random.ply"}) {
    const std::string path = (dir_ / name).string();
    fs::create_symlink(name[0] == 'z' ? "/dev/zero" : "/dev/urandom", path);
    Mesh m;
    const Status s = load_mesh(path, m);
    EXPECT_EQ(s.code(), StatusCode::kParseError) << s.message();
    EXPECT_EQ(s.message().rfind(path + ":", 0), 0u) << s.message();
    EXPECT_NE(s.message().find(": binary content (byte 0x"), std::string::npos) << s.message();
  }
  // A terminal colour's escape in a comment is found in text files (the OBJ reader skips comments).
  const std::string coloured = write("coloured.obj",
                                     "# \x1b[1mtetrahedron\x1b[0m\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                     "v 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  Mesh tet;
  const Status loaded = load_mesh(coloured, tet);
  EXPECT_TRUE(loaded.ok()) << loaded.message();
  EXPECT_EQ(tet.triangles.size(), 4u);
  // A control byte after the first 64 KiB is left to the reader (the OBJ reader names its line).
  const std::string late = write("late.obj", std::string(70000, '\n') + "v 0 0 0\x01\n");
  Mesh m;
  const Status s = load_mesh(late, m);
  EXPECT_EQ(s.message().rfind(late + ":70001: binary content (byte 0x01)", 0), 0u) << s.message();
}

// A binary PLY body is not text: a long run without a newline byte there is data, while the same
// run in an ASCII body is a line (ReadLimits::text_end, from the header's format line).
TEST_F(TempFiles, LineLimitStopsAtABinaryBody) {
  ReadLimits limits;
  limits.max_line_bytes = 64;
  limits.text_end = [](std::string_view head) -> size_t {
    const size_t end = head.find("END\n");
    return end == std::string_view::npos ? kTextNotEnded : end + 4;
  };
  std::string data;
  const std::string body(1000, 'b');
  EXPECT_TRUE(read_file(write("binary.bin", "header\nEND\n" + body), data, limits).ok());
  EXPECT_EQ(data, "header\nEND\n" + body);
  limits.text_end = nullptr;
  const std::string text = write("text.txt", "header\nEND\n" + body);
  const Status s = read_file(text, data, limits);
  EXPECT_EQ(s.code(), StatusCode::kParseError);
  EXPECT_EQ(s.message().rfind(text + ":3: line longer than 64 B", 0), 0u) << s.message();
  // The limit is on each line, a complete one too, wherever the buffer's chunks end.
  const std::string long_line = write("long.txt", "a\n" + std::string(65, 'x') + "\nb\n");
  EXPECT_EQ(read_file(long_line, data, limits).message().rfind(long_line + ":2: line longer", 0), 0u);
  limits.max_line_bytes = 65;
  EXPECT_TRUE(read_file(long_line, data, limits).ok());
}

// The same for load_mesh's PLY reader: a binary body of more than the line limit without a
// newline byte (6 million vertices at the origin: float zeros) loads, the header being the only
// text it checks.
TEST_F(TempFiles, BinaryPlyBodyIsNotLineChecked) {
  constexpr uint32_t kVertices = 6'000'000;
  ASSERT_GT(uint64_t(kVertices) * 12, kMaxMeshLineBytes);
  std::string file = ply_header("binary_little_endian", int(kVertices), 1);
  const size_t header = file.size();
  file.resize(header + size_t(kVertices) * 12, '\0');
  const float one = 1.0f;                        // 0x3f800000: no newline byte either
  std::memcpy(&file[header + 12], &one, 4);      // vertex 1 = (1, 0, 0)
  std::memcpy(&file[header + 24 + 4], &one, 4);  // vertex 2 = (0, 1, 0)
  const char face[13] = {3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0};
  file.append(face, sizeof face);
  ASSERT_EQ(file.find('\n', header), std::string::npos);
  Mesh m;
  const Status s = load_mesh(write("long_body.ply", file), m);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(m.positions.size(), kVertices);
  EXPECT_EQ(m.positions[2], vec3(0, 1, 0));
  EXPECT_EQ(m.triangles, std::vector<uvec3>{uvec3(0, 1, 2)});
}

// The total: a stream read stops one byte past the limit (the memory available by default), and a
// regular file larger than it is refused before any of it is read.
TEST_F(TempFiles, ReadStopsAtTheSizeLimit) {
  ReadLimits limits;
  limits.max_line_bytes = std::numeric_limits<uint64_t>::max();
  limits.max_bytes = 1 << 20;
  limits.text_end = [](std::string_view) { return size_t(0); };  // binary from the start: no text check
  std::string data;
  Status s = read_file("/dev/zero", data, limits);
  EXPECT_EQ(s.code(), StatusCode::kOutOfMemory);
  EXPECT_EQ(s.message(),
            "/dev/zero: more than the read limit of 1.0 MiB read without reaching the end (a stream "
            "that does not end?)");
  limits.max_bytes = 100;
  const std::string big = write("big.txt", std::string(101, 'x'));
  s = read_file(big, data, limits);
  EXPECT_EQ(s.code(), StatusCode::kOutOfMemory);
  EXPECT_EQ(s.message(), big + ": the file is 101 B, more than the read limit of 100 B");
  limits.max_bytes = 101;
  EXPECT_TRUE(read_file(big, data, limits).ok());
  EXPECT_EQ(data.size(), 101u);
}

}  // namespace
}  // namespace gwnrt
