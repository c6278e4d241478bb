// The README's code examples are the programs in examples/library, verbatim: each block between
// "// [readme-NAME-begin]" and "// [readme-NAME-end]" must stand in README.md as an indented code
// block (dedented, then indented by four spaces), so the README shows code that CI compiles.
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace {

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The marked lines of `source`, dedented by the first line's indentation, each indented by four.
std::string readme_block(const std::string& source, const std::string& name) {
  const std::string begin = "// [readme-" + name + "-begin]", end = "// [readme-" + name + "-end]";
  std::istringstream in(source);
  std::string line, block;
  bool inside = false;
  size_t indent = std::string::npos;
  while (std::getline(in, line)) {
    if (line.find(end) != std::string::npos) return block;
    if (inside) {
      if (indent == std::string::npos) indent = line.find_first_not_of(' ');
      const size_t cut = std::min(indent, line.find_first_not_of(' '));
      block += line.empty() ? "\n" : "    " + line.substr(cut == std::string::npos ? line.size() : cut) + "\n";
    }
    if (line.find(begin) != std::string::npos) inside = true;
  }
  return {};
}

}  // namespace

TEST(Readme, CodeExamplesAreTheCompiledPrograms) {
  const std::string root = GWNRT_SOURCE_DIR;
  const std::string readme = read_file(root + "/README.md");
  ASSERT_FALSE(readme.empty()) << "cannot read " << root << "/README.md";
  const struct {
    const char* file;
    const char* name;
  } blocks[] = {{"examples/library/main.cpp", "library"}, {"examples/library/embree_main.cpp", "embree"}};
  for (const auto& b : blocks) {
    const std::string block = readme_block(read_file(root + "/" + b.file), b.name);
    ASSERT_FALSE(block.empty()) << b.file << " has no readme-" << b.name << " block";
    EXPECT_NE(readme.find(block), std::string::npos)
        << "README.md does not show " << b.file << "'s readme-" << b.name << " block as it is:\n"
        << block;
  }
}
