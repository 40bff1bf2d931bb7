// SPDX-License-Identifier: Apache-2.0
#include <string>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "panoptes/config.h"
#include "temp_dir.h"

namespace panoptes {
namespace {

YamlReader reader_for(const std::string& text) {
  return YamlReader("test.yaml", YAML::Load(text));
}

TEST(Config, ConfigErrorMessageFormat) {
  const ConfigError with_key("a.yaml", "cameras[0].K", "expected a list of 4 numbers");
  EXPECT_STREQ(with_key.what(), "a.yaml: cameras[0].K: expected a list of 4 numbers");
  EXPECT_EQ(with_key.file(), "a.yaml");
  EXPECT_EQ(with_key.key(), "cameras[0].K");
  const ConfigError without_key("a.yaml", "", "cannot open file");
  EXPECT_STREQ(without_key.what(), "a.yaml: cannot open file");
}

TEST(Config, ReadsTypedValuesAndFallbacks) {
  const YamlReader reader = reader_for(
      "rate: 120.5\ncount: 7\nname: cam0\nenabled: true\nlist: [1, 2.5, -3]\n"
      "rows: [[1, 2, 3], [4, 5, 6]]\nblank:\nnested: {depth: 2}\n");
  EXPECT_DOUBLE_EQ(reader.get_double("rate"), 120.5);
  EXPECT_DOUBLE_EQ(reader.get_double("count"), 7.0);
  EXPECT_EQ(reader.get_int("count"), 7);
  EXPECT_EQ(reader.get_string("name"), "cam0");
  EXPECT_TRUE(reader.get_bool("enabled", false));
  EXPECT_EQ(reader.get_doubles("list"), (std::vector<double>{1, 2.5, -3}));
  EXPECT_EQ(reader.get_doubles("list", 3), (std::vector<double>{1, 2.5, -3}));
  EXPECT_EQ(reader.get_double_rows("rows", 3), (std::vector<std::vector<double>>{{1, 2, 3}, {4, 5, 6}}));
  EXPECT_EQ(reader.child("nested").get_int("depth"), 2);
  EXPECT_EQ(reader.child("nested").key_path(), "nested");

  EXPECT_DOUBLE_EQ(reader.get_double("absent", 4.5), 4.5);
  EXPECT_EQ(reader.get_int("absent", 9), 9);
  EXPECT_FALSE(reader.get_bool("absent", false));
  EXPECT_EQ(reader.get_string("absent", "x"), "x");
  // A key with no value counts as absent, so a user can blank an optional setting.
  EXPECT_FALSE(reader.has("blank"));
  EXPECT_DOUBLE_EQ(reader.get_double("blank", 1.25), 1.25);
  EXPECT_TRUE(reader.has("rate"));
  EXPECT_FALSE(reader.has("absent"));
  EXPECT_TRUE(reader.sequence_or_empty("absent").empty());
}

TEST(Config, ErrorsNameTheFullKeyPath) {
  const YamlReader root = reader_for(
      "cameras:\n"
      "  - {id: a, K: [1, 2, 3, 4]}\n"
      "  - {id: b, K: [1, 2, 3, 4]}\n"
      "  - {id: c, K: [1, 2, 3], rate: fast, n: 1.5, on: maybe, sub: [1, 2], m: [[1, 2], [3]], s: [x]}\n");
  const std::vector<YamlReader> cameras = root.sequence("cameras");
  ASSERT_EQ(cameras.size(), 3u);
  EXPECT_EQ(cameras[2].key_path(), "cameras[2]");
  EXPECT_EQ(cameras[2].key_of("K"), "cameras[2].K");
  EXPECT_EQ(config_error_of([&] { cameras[2].get_doubles("K", 4); }),
            "test.yaml: cameras[2].K: expected a list of 4 numbers, got 3");
  EXPECT_EQ(config_error_of([&] { cameras[2].get_double("rate"); }),
            "test.yaml: cameras[2].rate: expected a number, got 'fast'");
  EXPECT_EQ(config_error_of([&] { cameras[2].get_int("n"); }),
            "test.yaml: cameras[2].n: expected an integer, got '1.5'");
  EXPECT_EQ(config_error_of([&] { cameras[2].get_bool("on", false); }),
            "test.yaml: cameras[2].on: expected true or false, got 'maybe'");
  EXPECT_EQ(config_error_of([&] { cameras[2].get_double("missing"); }),
            "test.yaml: cameras[2].missing: missing key");
  EXPECT_EQ(config_error_of([&] { cameras[2].get_string("sub"); }),
            "test.yaml: cameras[2].sub: expected a string");
  EXPECT_EQ(config_error_of([&] { cameras[2].get_double_rows("m", 2); }),
            "test.yaml: cameras[2].m[1]: expected a list of 2 numbers, got 1");
  EXPECT_EQ(config_error_of([&] { cameras[2].get_doubles("s"); }),
            "test.yaml: cameras[2].s[0]: expected a number, got 'x'");
  EXPECT_EQ(config_error_of([&] { cameras[2].get_doubles("rate"); }),
            "test.yaml: cameras[2].rate: expected a list of numbers");
  EXPECT_EQ(config_error_of([&] { cameras[2].sequence("id"); }), "test.yaml: cameras[2].id: expected a list");
  EXPECT_EQ(config_error_of([&] { root.child("nothing"); }), "test.yaml: nothing: missing key");
  EXPECT_EQ(config_error_of([&] { cameras[1].fail("K", "singular"); }), "test.yaml: cameras[1].K: singular");
}

TEST(Config, NonMapNodeIsReported) {
  const YamlReader root = reader_for("items: [3]\n");
  const auto items = root.sequence("items");
  EXPECT_EQ(config_error_of([&] { items[0].get_double("x"); }), "test.yaml: items[0]: expected a map");
}

TEST(Config, CopiedReaderSharesTheNode) {
  const YamlReader original = reader_for("a: 1\n");
  const YamlReader copy(original);  // NOLINT(performance-unnecessary-copy-initialization): tests the copy
  EXPECT_EQ(copy.get_int("a"), 1);
  EXPECT_EQ(copy.file(), "test.yaml");
}

TEST(Config, LoadYamlFileReportsMissingFile) {
  const std::string message = config_error_of([] { load_yaml_file("/nonexistent/dir/settings.yaml"); });
  EXPECT_EQ(message, "/nonexistent/dir/settings.yaml: cannot open file");
}

TEST(Config, LoadYamlFileReportsSyntaxErrorLine) {
  testing::TempDir dir;
  const auto path = dir.write("broken.yaml", "a: 1\nb: [1, 2\nc: 3\n");
  const std::string message = config_error_of([&] { load_yaml_file(path); });
  EXPECT_NE(message.find(path.string() + ": "), std::string::npos) << message;
  EXPECT_NE(message.find("line "), std::string::npos) << message;
}

TEST(Config, LoadYamlFileReadsContent) {
  testing::TempDir dir;
  const auto path = dir.write("ok.yaml", "threshold: 42\n");
  const YamlReader reader(path.string(), load_yaml_file(path));
  EXPECT_EQ(reader.get_int("threshold"), 42);
}

}  // namespace
}  // namespace panoptes
