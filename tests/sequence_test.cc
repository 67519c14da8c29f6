#include "lsgd/io/sequence.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "lsgd/io/config.h"
#include "lsgd/limits.h"
#include "sequence_test_support.h"
#include "test_util.h"

namespace lsgd::io {
namespace {

namespace fs = std::filesystem;
using lsgd::test::expect_error;

using test_support::random_image;
using test_support::read_bytes;
using test_support::same;
using test_support::SequenceTest;

// ---------------------------------------------------------------- natural_less

TEST(NaturalLess, NumbersCompareByValue) {
  EXPECT_TRUE(natural_less("2.jpg", "10.jpg"));
  EXPECT_FALSE(natural_less("10.jpg", "2.jpg"));
  EXPECT_TRUE(natural_less("img9", "img10"));
  EXPECT_TRUE(natural_less("img10", "img100"));
  EXPECT_TRUE(natural_less("img9", "img100"));
  EXPECT_FALSE(natural_less("img100", "img10"));
}

TEST(NaturalLess, SortsAMixedList) {
  std::vector<std::string> names = {"img100.png", "img10.png", "b1",     "img9.png",
                                    "a10b2",      "a10b10",    "a9",     "img2.png",
                                    "a10",        "img1.png",  "frame_", "a10b"};
  std::sort(names.begin(), names.end(), natural_less);
  const std::vector<std::string> expected = {"a9",       "a10",      "a10b",      "a10b2",
                                             "a10b10",   "b1",       "frame_",    "img1.png",
                                             "img2.png", "img9.png", "img10.png", "img100.png"};
  EXPECT_EQ(names, expected);
}

TEST(NaturalLess, LeadingZerosCompareByValueThenZeroCount) {
  EXPECT_TRUE(natural_less("000009.png", "000010.png"));
  EXPECT_TRUE(natural_less("img001", "img2"));
  EXPECT_TRUE(natural_less("img9", "img010"));
  // Same value: a total order that puts fewer leading zeros first.
  EXPECT_TRUE(natural_less("img1", "img01"));
  EXPECT_FALSE(natural_less("img01", "img1"));
  EXPECT_TRUE(natural_less("img01", "img001"));
  // The value decides before the zero count does.
  EXPECT_TRUE(natural_less("a01b1", "a1b2"));
}

TEST(NaturalLess, LongDigitRunsDoNotOverflow) {
  const std::string big(30, '9');                         // 30 digits
  const std::string bigger = "1" + std::string(30, '0');  // 31 digits
  EXPECT_TRUE(natural_less("f" + big, "f" + bigger));
  EXPECT_FALSE(natural_less("f" + bigger, "f" + big));
  const std::string a = "1" + std::string(28, '0') + "1";  // 30 digits
  const std::string b = "1" + std::string(28, '0') + "2";
  EXPECT_TRUE(natural_less(a, b));
  EXPECT_TRUE(natural_less("2", std::string(29, '0') + "3"));
  EXPECT_TRUE(natural_less(std::string(29, '0') + "3", "4"));
}

TEST(NaturalLess, IsAStrictTotalOrder) {
  const std::vector<std::string> names = {"",    "a",  "a0", "a00", "a1", "a01", "a1b", "a01a",
                                          "a10", "a9", "1",  "01",  "b",  "a-1", "a~",  "A1"};
  for (const std::string& x : names) {
    EXPECT_FALSE(natural_less(x, x)) << x;
    for (const std::string& y : names) {
      if (x == y) continue;
      EXPECT_NE(natural_less(x, y), natural_less(y, x)) << "'" << x << "' vs '" << y << "'";
      for (const std::string& z : names) {
        if (natural_less(x, y) && natural_less(y, z)) {
          EXPECT_TRUE(natural_less(x, z)) << x << " < " << y << " < " << z;
        }
      }
    }
  }
}

// ---------------------------------------------------------------- open_sequence

TEST_F(SequenceTest, FolderListsImagesInNaturalOrder) {
  for (const char* name : {"10.png", "2.PNG", "1.JpEg", "3.jpg", "4.bmp", "5.pgm", "6.ppm", "7.tif",
                           "8.TIFF", "notes.txt", "11.png.bak", "noext"}) {
    write(name, "x");
  }
  fs::create_directories(dir_ / "9.png");  // a folder with an image name keeps its place
  write("sub/0.png", "x");                 // subfolders are not searched
  const Sequence seq = open_sequence(dir_.string());
  EXPECT_EQ(seq.source, dir_.string());
  std::vector<std::string> expected;
  for (const char* name :
       {"1.JpEg", "2.PNG", "3.jpg", "4.bmp", "5.pgm", "6.ppm", "7.tif", "8.TIFF", "9.png",
        "10.png"}) {
    expected.push_back(path(name));
  }
  EXPECT_EQ(seq.images, expected);
}

TEST_F(SequenceTest, ListFileResolvesRelativeAndAbsolutePaths) {
  const std::string absolute = path("elsewhere/abs.png");
  const std::string list = write("lists/seq.txt",
                                 "# a comment\r\n"
                                 "b.png\r\n"
                                 "\r\n"
                                 "   \n"
                                 "sub/a.png  \r\n"
                                 "#skipped.png\n"
                                 "../up.png\n" +
                                     absolute + "\r\n" + "last.png");  // no final newline
  const Sequence seq = open_sequence(list);
  EXPECT_EQ(seq.source, list);
  const fs::path base = dir_ / "lists";
  const std::vector<std::string> expected = {
      (base / "b.png").string(), (base / "sub/a.png").string(), (base / "../up.png").string(),
      absolute, (base / "last.png").string()};
  EXPECT_EQ(seq.images, expected);
}

// A byte-order mark (Notepad's UTF-8) is not part of the first path.
TEST_F(SequenceTest, ListFileWithAByteOrderMark) {
  const std::string list = write("bom.txt", "\xEF\xBB\xBF" "10.png\n2.png\n");
  const std::vector<std::string> expected = {path("10.png"), path("2.png")};
  EXPECT_EQ(open_sequence(list).images, expected);
  std::istringstream none("abc");
  EXPECT_FALSE(skip_utf8_bom(none));
  EXPECT_EQ(none.get(), 'a');
}

// Lists joined with cat keep each file's BOM: one in the middle is dropped too.
TEST_F(SequenceTest, ListFilesJoinedWithTheirByteOrderMarks) {
  const std::string list = write("bom2.txt", "\xEF\xBB\xBF" "10.png\n\xEF\xBB\xBF" "2.png\n");
  const std::vector<std::string> expected = {path("10.png"), path("2.png")};
  EXPECT_EQ(open_sequence(list).images, expected);
}

TEST_F(SequenceTest, ListFileKeepsItsOrderAndDoesNotCheckFiles) {
  const std::string list = write("seq.txt", "10.png\n2.png\nmissing.png\n");
  const Sequence seq = open_sequence(list);
  const std::vector<std::string> expected = {path("10.png"), path("2.png"), path("missing.png")};
  EXPECT_EQ(seq.images, expected);
}

TEST_F(SequenceTest, MissingPathIsIoError) {
  const std::string missing = path("nope");
  expect_error<IoError>([&] { open_sequence(missing); }, {missing, "does not exist"});
}

TEST_F(SequenceTest, EmptyFolderIsFormatError) {
  const std::string empty = path("empty");
  fs::create_directories(empty);
  expect_error<FormatError>([&] { open_sequence(empty); }, {empty, "no images", ".png"});
  write("empty/readme.txt", "not an image");
  expect_error<FormatError>([&] { open_sequence(empty); }, {empty, "no images"});
}

TEST_F(SequenceTest, EmptyListIsFormatError) {
  const std::string empty = write("empty.txt", "");
  expect_error<FormatError>([&] { open_sequence(empty); }, {empty});
  const std::string comments = write("comments.txt", "# only\r\n\r\n   \n# comments\n");
  expect_error<FormatError>([&] { open_sequence(comments); }, {comments});
}

// A line longer than any path the system opens names no file: the list is
// refused, naming the line. Skipped, each such entry was named whole,
// twice, on its skip line (a 1 MB list of 15 wrote 2 MB on stderr).
TEST_F(SequenceTest, AListLineLongerThanAnyPathIsFormatErrorNamingIt) {
  const std::string list = write("long.txt", "a.png\n" + std::string(65000, 'x') + ".png\n");
  expect_error<FormatError>([&] { read_image_list(list); },
                            {list, "line 2 is 65004 bytes long", "more than any path the system opens (4095)"});
  const std::string longest = write("longest.txt", "a.png\n" + std::string(4091, 'y') + ".png\n");
  EXPECT_EQ(read_image_list(longest).size(), 2u);
}

TEST_F(SequenceTest, SingleImageIsNotASequence) {
  const std::string image = write("frame.png", "x");
  expect_error<FormatError>([&] { open_sequence(image); }, {image});
}

TEST_F(SequenceTest, UnreadableFolderIsIoError) {
  if (::geteuid() == 0) GTEST_SKIP() << "root reads every folder";
  const std::string locked = path("locked");
  fs::create_directories(locked);
  write("locked/1.png", "x");
  fs::permissions(locked, fs::perms::none);
  expect_error<IoError>([&] { open_sequence(locked); }, {locked});
  fs::permissions(locked, fs::perms::owner_all);
}

}  // namespace
}  // namespace lsgd::io
