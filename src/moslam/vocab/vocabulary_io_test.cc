#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"
#include "moslam/vocab/test_descriptors.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::vocab {
namespace {

using ::testing::HasSubstr;

Vocabulary SmallVocabulary(uint64_t seed) {
  cv::RNG rng(seed);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 12; ++i) images.push_back(test::RandomDescriptors(150, rng));
  VocabularyTrainOptions options;
  options.k = 6;
  options.levels = 3;
  return Vocabulary::Train(images, options);
}

std::string ReadBytes(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream s;
  s << file.rdbuf();
  return s.str();
}

TEST(VocabularyIo, BinaryRoundTripGivesIdenticalTransforms) {
  const Vocabulary voc = SmallVocabulary(1);
  testing::TempDir dir;
  const std::string path = dir.path() + "/voc.mvoc";
  voc.Save(path);
  const Vocabulary loaded = Vocabulary::Load(path);
  EXPECT_EQ(loaded.k(), voc.k());
  EXPECT_EQ(loaded.levels(), voc.levels());
  ASSERT_EQ(loaded.size(), voc.size());
  EXPECT_EQ(loaded.num_nodes(), voc.num_nodes());
  for (WordId w = 0; w < voc.size(); ++w) EXPECT_EQ(loaded.Weight(w), voc.Weight(w));
  cv::RNG rng(99);
  const cv::Mat probe = test::RandomDescriptors(500, rng);
  BowVector bow_a, bow_b;
  FeatureVector fv_a, fv_b;
  voc.Transform(probe, &bow_a, &fv_a, 1);
  loaded.Transform(probe, &bow_b, &fv_b, 1);
  EXPECT_EQ(bow_a, bow_b);  // exact: weights are stored as IEEE doubles
  EXPECT_EQ(fv_a, fv_b);
  // Saving the loaded vocabulary reproduces the file byte for byte.
  const std::string again = dir.path() + "/again.mvoc";
  loaded.Save(again);
  EXPECT_EQ(ReadBytes(path), ReadBytes(again));
}

TEST(VocabularyIo, TruncatedOrDamagedFilesAreInputErrorsNamingTheFile) {
  const Vocabulary voc = SmallVocabulary(2);
  testing::TempDir dir;
  const std::string path = dir.path() + "/voc.mvoc";
  voc.Save(path);
  const std::string bytes = ReadBytes(path);
  for (size_t length :
       {size_t{4}, size_t{8}, size_t{20}, size_t{30}, bytes.size() / 2, bytes.size() - 1}) {
    const std::string cut = dir.Write("cut.mvoc", bytes.substr(0, length));
    EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(cut); }), HasSubstr(cut))
        << "length " << length;
  }
  const std::string longer = dir.Write("long.mvoc", bytes + "x");
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(longer); }), HasSubstr("unexpected bytes"));
  std::string bad_parent = bytes;
  bad_parent[28] = 5;  // node 1's parent: must precede it
  const std::string bad = dir.Write("bad.mvoc", bad_parent);
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(bad); }), HasSubstr("does not precede"));
  const std::string garbage = dir.Write("garbage.mvoc", "hello");
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(garbage); }), HasSubstr("not a vocabulary"));
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(dir.path() + "/missing"); }),
              HasSubstr("cannot open"));
}

// A DBoW2 line: parent, leaf flag, 32 bytes all equal to `byte` except byte 0 = `first`, weight.
std::string Dbow2Line(int parent, int leaf, int first, int byte, const std::string& weight) {
  std::string line =
      std::to_string(parent) + " " + std::to_string(leaf) + " " + std::to_string(first);
  for (int i = 1; i < 32; ++i) line += " " + std::to_string(byte);
  return line + " " + weight + "\n";
}

// k = 2, L = 2: nodes 1 (bytes 0) and 2 (bytes 255) under the root; words 3, 4 under node 1
// and 5, 6 under node 2, as ORB-SLAM2's ORBvoc.txt lists them.
std::string TinyDbow2Text() {
  return "2 2 0 0\n" + Dbow2Line(0, 0, 0, 0, "0") + Dbow2Line(0, 0, 255, 255, "0") +
         Dbow2Line(1, 1, 0, 0, "0.5") + Dbow2Line(1, 1, 255, 0, "1.25") +
         Dbow2Line(2, 1, 0, 255, "0.75") + Dbow2Line(2, 1, 255, 255, "2e-1") + "\n";
}

TEST(VocabularyIo, LoadsDbow2TextVocabularies) {
  testing::TempDir dir;
  const std::string path = dir.Write("ORBvoc.txt", TinyDbow2Text());
  const Vocabulary voc = Vocabulary::Load(path);
  EXPECT_EQ(voc.k(), 2);
  EXPECT_EQ(voc.levels(), 2);
  ASSERT_EQ(voc.size(), 4u);
  EXPECT_EQ(voc.num_nodes(), 7u);
  EXPECT_DOUBLE_EQ(voc.Weight(0), 0.5);
  EXPECT_DOUBLE_EQ(voc.Weight(1), 1.25);
  EXPECT_DOUBLE_EQ(voc.Weight(2), 0.75);
  EXPECT_DOUBLE_EQ(voc.Weight(3), 0.2);
  uint8_t d[32] = {};
  d[0] = 250;  // near node 1 (mostly zeros), then nearer word 1 (first byte 255)
  EXPECT_EQ(voc.Transform(d), 1u);
  std::memset(d, 255, 32);
  d[0] = 3;
  EXPECT_EQ(voc.Transform(d), 2u);
  // DBoW2 text and our binary format describe the same tree.
  const std::string binary = dir.path() + "/tiny.mvoc";
  voc.Save(binary);
  const Vocabulary again = Vocabulary::Load(binary);
  ASSERT_EQ(again.size(), 4u);
  for (WordId w = 0; w < 4; ++w) {
    EXPECT_EQ(again.Weight(w), voc.Weight(w));
    EXPECT_EQ(std::memcmp(again.WordDescriptor(w), voc.WordDescriptor(w), 32), 0);
  }
}

TEST(VocabularyIo, MalformedDbow2TextNamesFileAndLine) {
  testing::TempDir dir;
  std::string text = TinyDbow2Text();
  const std::string short_line = dir.Write("a.txt", "2 2 0 0\n0 0 1 2 3\n");
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(short_line); }),
              HasSubstr(short_line + ":2:"));
  const std::string bad_byte = dir.Write("b.txt", "2 2 0 0\n" + Dbow2Line(0, 1, 300, 0, "1"));
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(bad_byte); }), HasSubstr("[0, 255]"));
  const std::string bad_parent = dir.Write("c.txt", "2 2 0 0\n" + Dbow2Line(3, 1, 0, 0, "1"));
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(bad_parent); }),
              HasSubstr(bad_parent + ":2: parent 3"));
  const std::string scoring = dir.Write("d.txt", "2 2 1 0\n" + Dbow2Line(0, 1, 0, 0, "1"));
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(scoring); }), HasSubstr("only L1"));
  const std::string header = dir.Write("e.txt", "10\n");
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(header); }), HasSubstr(header + ":1:"));
  const std::string no_weight = dir.Write("f.txt", "2 2 0 0\n" + Dbow2Line(0, 1, 0, 0, ""));
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(no_weight); }), HasSubstr("weight"));
  const std::string leafless = dir.Write("g.txt", "2 2 0 0\n" + Dbow2Line(0, 0, 0, 0, "0"));
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(leafless); }), HasSubstr("no children"));
}

// Issue 31: weights that are not finite or are negative were loaded and used in every score.
TEST(VocabularyIo, NonFiniteOrNegativeWeightsAreRefusedNamingNodeOrLine) {
  testing::TempDir dir;
  for (const char* weight : {"nan", "inf", "-0.5"}) {
    std::string text = "2 2 0 0\n" + Dbow2Line(0, 0, 0, 0, "0") + Dbow2Line(0, 0, 255, 255, "0") +
                       Dbow2Line(1, 1, 0, 0, "0.5") + Dbow2Line(1, 1, 255, 0, weight) +
                       Dbow2Line(2, 1, 0, 255, "0.75") + Dbow2Line(2, 1, 255, 255, "2e-1");
    const std::string path = dir.Write("w.txt", text);
    EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(path); }),
                ::testing::AllOf(HasSubstr(path + ":5:"), HasSubstr("weight")))
        << weight;
  }
  // The binary format: the tiny tree's first word (node 3) keeps its weight in bytes 139-146
  // (header 28 bytes, two inner nodes of 37, then node 3's parent, flag and descriptor).
  const std::string text_path = dir.Write("tiny.txt", TinyDbow2Text());
  const std::string binary = dir.path() + "/tiny.mvoc";
  Vocabulary::Load(text_path).Save(binary);
  const std::string bytes = ReadBytes(binary);
  for (const double weight : {std::nan(""), HUGE_VAL, -1.0}) {
    std::string damaged = bytes;
    ASSERT_EQ(std::memcmp(damaged.data() + 139, "\0\0\0\0\0\0\xe0\x3f", 8), 0);  // 0.5
    std::memcpy(damaged.data() + 139, &weight, 8);  // little-endian, as the format
    const std::string path = dir.Write("w.mvoc", damaged);
    EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(path); }),
                ::testing::AllOf(HasSubstr(path), HasSubstr("node 3"), HasSubstr("weight")))
        << weight;
  }
}

TEST(VocabularyIo, TextNodeLinesAreParsedStrictly) {
  // 31 descriptor bytes: "0.5" must not be read as the 32nd byte 0 and the weight ".5".
  testing::TempDir dir;
  std::string line = "1 1";
  for (int i = 0; i < 31; ++i) line += " 7";
  const std::string path =
      dir.Write("short.txt", "2 2 0 0\n" + Dbow2Line(0, 0, 0, 0, "0") + line + " 0.5\n");
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(path); }),
              ::testing::AllOf(HasSubstr(path + ":3:"), HasSubstr("32 descriptor bytes")));
  const std::string glued = dir.Write("glued.txt", "2 2 0 0\n0 1x 0" + std::string(" 1") + "\n");
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(glued); }), HasSubstr(glued + ":2:"));
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Load(dir.path()); }),
              ::testing::AllOf(HasSubstr(dir.path()), HasSubstr("is a directory")));
}

}  // namespace
}  // namespace moslam::vocab
