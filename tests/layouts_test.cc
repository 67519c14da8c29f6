// Tests of the dataset layouts and frame subsampling (io/layouts.h) on tiny
// copies of each layout written into a temporary folder.
#include "lsgd/io/layouts.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "test_util.h"

namespace lsgd::io {
namespace {

namespace fs = std::filesystem;
using lsgd::test::expect_error;

std::string kitti_name(int i) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06d.png", i);
  return name;
}

std::vector<std::string> names_of(const Sequence& s) {
  std::vector<std::string> names;
  for (const auto& p : s.images) names.push_back(fs::path(p).filename().string());
  return names;
}

class LayoutTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(LSGD_TEST_TMP) /
           (std::string("layouts_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A small real PNG (different content per call).
  void image(const fs::path& path) {
    fs::create_directories(path.parent_path());
    cv::Mat m(6, 8, CV_8UC1, cv::Scalar(static_cast<double>(++count_ % 256)));
    ASSERT_TRUE(cv::imwrite(path.string(), m)) << path;
  }
  void text(const fs::path& path, const std::string& content) {
    fs::create_directories(path.parent_path());
    std::ofstream(path) << content;
  }
  // dataset/sequences/<nn>/image_<camera>/000000.png ... and times.txt with `stamps` lines.
  fs::path kitti(const std::string& nn, std::vector<int> cameras, int frames, int stamps) {
    const fs::path seq = dir_ / "dataset" / "sequences" / nn;
    for (int c : cameras) {
      for (int i = 0; i < frames; ++i) image(seq / ("image_" + std::to_string(c)) / kitti_name(i));
    }
    std::string times;
    for (int i = 0; i < stamps; ++i) times += std::to_string(0.1 * i) + "\n";
    text(seq / "times.txt", times);
    return seq;
  }
  // A FAB-MAP folder with files 0001.jpg .. <n>.jpg.
  fs::path fabmap(int n) {
    const fs::path folder = dir_ / "Images";
    for (int i = 1; i <= n; ++i) {
      char name[32];
      std::snprintf(name, sizeof(name), "%04d.jpg", i);
      image(folder / name);
    }
    return folder;
  }

  fs::path dir_;
  int count_ = 0;
};

// ---------------------------------------------------------------- names and options

TEST(LayoutNames, ParseAndPrintRoundTrip) {
  for (const char* name : {"auto", "folder", "list", "kitti", "fabmap", "neu"}) {
    EXPECT_EQ(parse_layout(name), name);
  }
  const std::vector<std::string> names = layout_names();
  ASSERT_GE(names.size(), 6u);
  EXPECT_EQ(std::vector<std::string>(names.begin(), names.begin() + 6),
            (std::vector<std::string>{"auto", "folder", "list", "kitti", "fabmap", "neu"}));
  for (const char* name : {"left", "right", "both"}) EXPECT_EQ(to_string(parse_side(name)), name);
  expect_error<InvalidArgument>([] { parse_layout("KITTI"); }, {"KITTI", "fabmap"});
  expect_error<InvalidArgument>([] { parse_side("middle"); }, {"middle"});
}

TEST(FrameSelection, KeepsEveryKthFrameBetweenFirstAndLast) {
  EXPECT_EQ((FrameSelection{0, -1, 3}.kept(10)), (std::vector<std::int64_t>{0, 3, 6, 9}));
  EXPECT_EQ((FrameSelection{1, -1, 3}.kept(10)), (std::vector<std::int64_t>{1, 4, 7}));
  EXPECT_EQ((FrameSelection{2, 7, 2}.kept(10)), (std::vector<std::int64_t>{2, 4, 6}));
  EXPECT_EQ((FrameSelection{4, 4, 5}.kept(10)), (std::vector<std::int64_t>{4}));
  EXPECT_EQ((FrameSelection{}.kept(3)), (std::vector<std::int64_t>{0, 1, 2}));
  EXPECT_TRUE(FrameSelection{}.keeps_all());
  EXPECT_FALSE((FrameSelection{0, -1, 2}.keeps_all()));
}

TEST(FrameSelection, RejectsInvalidOrOutOfRangeSelections) {
  expect_error<InvalidArgument>([] { FrameSelection{0, -1, 0}.check(); }, {"every", "0"});
  expect_error<InvalidArgument>([] { FrameSelection{-1, -1, 1}.check(); }, {"first", "-1"});
  expect_error<InvalidArgument>([] { FrameSelection{5, 3, 1}.check(); }, {"last = 3", "first = 5"});
  expect_error<InvalidArgument>(
      [] {
        FrameSelection{10, -1, 1}.kept(10);
      },
      {"first = 10", "10 frames"});
  expect_error<InvalidArgument>(
      [] {
        FrameSelection{0, 12, 1}.kept(10);
      },
      {"last = 12", "10 frames"});
}

// ---------------------------------------------------------------- folder, list, neu

TEST_F(LayoutTest, AutoOpensFoldersAndListFilesAsBefore) {
  for (const char* name : {"10.png", "2.png", "1.png"}) image(dir_ / "f" / name);
  text(dir_ / "list.txt", "f/10.png\nf/1.png\n");
  EXPECT_EQ(detect_layout((dir_ / "f").string()), std::string(kFolderLayout));
  EXPECT_EQ(detect_layout((dir_ / "list.txt").string()), std::string(kListLayout));
  const Sequence folder = open_sequence((dir_ / "f").string(), SequenceOptions{});
  EXPECT_EQ(names_of(folder), (std::vector<std::string>{"1.png", "2.png", "10.png"}));
  EXPECT_EQ(folder.images, open_sequence((dir_ / "f").string()).images);
  const Sequence list = open_sequence((dir_ / "list.txt").string(), SequenceOptions{});
  EXPECT_EQ(names_of(list), (std::vector<std::string>{"10.png", "1.png"}));
}

// docs/design.md's recipe from outside the library: a layout of one's own
// ("reversed": a folder marked by a REVERSED file, its images last first),
// registered, detected by "auto", opened by name, listed among the choices.
Sequence open_reversed(const std::string& path, const SequenceOptions&) {
  Sequence s = open_sequence(path);
  std::reverse(s.images.begin(), s.images.end());
  return s;
}
bool detect_reversed(const std::string& path, const SequenceOptions&) {
  return fs::exists(fs::path(path) / "REVERSED");
}

TEST_F(LayoutTest, ALayoutRegisteredFromOutsideIsDetectedOpenedAndListed) {
  static const bool registered = [] {
    register_layout({"reversed", "a folder marked REVERSED, last image first", open_reversed,
                     detect_reversed});
    return true;
  }();
  ASSERT_TRUE(registered);
  for (const char* name : {"1.png", "2.png", "3.png"}) image(dir_ / "r" / name);
  text(dir_ / "r" / "REVERSED", "");
  const std::string path = (dir_ / "r").string();
  EXPECT_EQ(detect_layout(path), "reversed");
  EXPECT_EQ(names_of(open_sequence(path, SequenceOptions{})),
            (std::vector<std::string>{"3.png", "2.png", "1.png"}));
  SequenceOptions by_name;
  by_name.layout = parse_layout("reversed");
  FrameSelection every_other{0, -1, 2};
  by_name.selection = every_other;
  EXPECT_EQ(names_of(open_sequence(path, by_name)), (std::vector<std::string>{"3.png", "1.png"}));
  SequenceOptions folder;
  folder.layout = kFolderLayout;  // a name given wins over detection
  EXPECT_EQ(names_of(open_sequence(path, folder)),
            (std::vector<std::string>{"1.png", "2.png", "3.png"}));
  const std::vector<std::string> names = layout_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "reversed"), names.end());
  expect_error<InvalidArgument>([] { register_layout({"reversed", "again", open_reversed}); },
                                {"register_layout", "reversed", "already registered"});
  expect_error<InvalidArgument>([] { register_layout({"auto", "no", open_reversed}); },
                                {"'auto' is not a layout name"});
  expect_error<InvalidArgument>([] { register_layout({"empty", "no open function", nullptr}); },
                                {"register_layout", "needs a name, a summary and a function"});
  SequenceOptions unknown;
  unknown.layout = "upside-down";
  expect_error<InvalidArgument>([&] { open_sequence(path, unknown); },
                                {"layout 'upside-down' is unknown: expected auto, folder", "or reversed"});
}

TEST_F(LayoutTest, ExplicitLayoutMustFitThePath) {
  image(dir_ / "f" / "1.png");
  text(dir_ / "list.txt", "f/1.png\n");
  SequenceOptions list;
  list.layout = std::string(kListLayout);
  expect_error<InvalidArgument>([&] { open_sequence((dir_ / "f").string(), list); },
                                {"f", "is a folder"});
  SequenceOptions folder;
  folder.layout = std::string(kFolderLayout);
  expect_error<InvalidArgument>([&] { open_sequence((dir_ / "list.txt").string(), folder); },
                                {"list.txt", "is a file"});
  expect_error<IoError>([&] { open_sequence((dir_ / "nope").string(), SequenceOptions{}); },
                        {"nope", "does not exist"});
}

TEST_F(LayoutTest, NeuOrdersNamesByteWiseLikeTheAuthorsCode) {
  // Unpadded counters and timestamps with fractions of varying length: their
  // code sorts the names as strings, so frame k is the k-th name in byte order.
  for (const char* name : {"1.png", "2.png", "10.png", "1650000000.25.png", "1650000000.5.png"}) {
    image(dir_ / "neu" / name);
  }
  SequenceOptions neu;
  neu.layout = std::string(kNeuLayout);
  EXPECT_EQ(names_of(open_sequence((dir_ / "neu").string(), neu)),
            (std::vector<std::string>{"1.png", "10.png", "1650000000.25.png", "1650000000.5.png",
                                      "2.png"}));
  EXPECT_EQ(names_of(open_sequence((dir_ / "neu").string(), SequenceOptions{})),
            (std::vector<std::string>{"1.png", "2.png", "10.png", "1650000000.5.png",
                                      "1650000000.25.png"}));
}

// ---------------------------------------------------------------- KITTI

TEST_F(LayoutTest, KittiFromTheDatasetRootWithASequenceNumber) {
  kitti("05", {0, 2}, 3, 3);
  SequenceOptions options;
  options.kitti_sequence = "5";  // "05"
  EXPECT_EQ(detect_layout((dir_ / "dataset").string(), options), std::string(kKittiLayout));
  const Sequence s = open_sequence((dir_ / "dataset").string(), options);
  ASSERT_EQ(s.images.size(), 3u);
  EXPECT_EQ(fs::path(s.images[0]), dir_ / "dataset/sequences/05/image_0/000000.png");
  EXPECT_EQ(fs::path(s.images[2]), dir_ / "dataset/sequences/05/image_0/000002.png");
  options.camera = 2;
  EXPECT_EQ(fs::path(open_sequence((dir_ / "dataset").string(), options).images[1]),
            dir_ / "dataset/sequences/05/image_2/000001.png");
  options.kitti_sequence = "07";
  expect_error<IoError>([&] { open_sequence((dir_ / "dataset").string(), options); },
                        {"sequences/07", "does not exist"});
}

TEST_F(LayoutTest, KittiSequenceFolderIsDetectedAutomatically) {
  const fs::path seq = kitti("00", {0, 1}, 12, 12);
  EXPECT_EQ(detect_layout(seq.string()), std::string(kKittiLayout));
  EXPECT_EQ(detect_layout(seq.string() + "/"), std::string(kKittiLayout));
  const Sequence s = open_sequence(seq.string(), SequenceOptions{});
  ASSERT_EQ(s.images.size(), 12u);
  for (int i = 0; i < 12; ++i) {  // 000010 after 000009: frame order is numeric
    EXPECT_EQ(fs::path(s.images[static_cast<std::size_t>(i)]), seq / "image_0" / kitti_name(i));
  }
  EXPECT_EQ(s.source, (seq / "image_0").string());
  // times.txt gives each frame its stamp; a selection keeps its frames' stamps.
  ASSERT_EQ(s.stamps.size(), 12u);
  EXPECT_EQ(s.stamps[11], std::stod(std::to_string(0.1 * 11)));
  SequenceOptions every;
  every.selection = {1, -1, 5};
  const Sequence picked = open_sequence(seq.string(), every);
  EXPECT_EQ(picked.stamps, (std::vector<double>{s.stamps[1], s.stamps[6], s.stamps[11]}));
  SequenceOptions folder;
  folder.layout = std::string(kFolderLayout);
  EXPECT_TRUE(open_sequence((seq / "image_0").string(), folder).stamps.empty());
}

TEST_F(LayoutTest, KittiImageFolderItselfNamesTheCamera) {
  const fs::path seq = kitti("00", {0, 1}, 2, 2);
  EXPECT_EQ(detect_layout((seq / "image_1").string()), std::string(kKittiLayout));
  const Sequence s = open_sequence((seq / "image_1").string(), SequenceOptions{});
  EXPECT_EQ(fs::path(s.images[1]), seq / "image_1" / kitti_name(1));
  SequenceOptions options;
  options.camera = 0;
  expect_error<InvalidArgument>([&] { open_sequence((seq / "image_1").string(), options); },
                                {"camera 0", "image_1"});
  // Without times.txt beside it, an image_X folder is a plain folder.
  image(dir_ / "plain" / "image_0" / "000000.png");
  EXPECT_EQ(detect_layout((dir_ / "plain" / "image_0").string()), std::string(kFolderLayout));
}

TEST_F(LayoutTest, KittiWithoutTheCameraFolderNamesWhatItHas) {
  const fs::path seq = kitti("00", {2, 3}, 2, 2);
  expect_error<FormatError>([&] { open_sequence(seq.string(), SequenceOptions{}); },
                            {seq.string(), "no image_0", "gray left", "image_2, image_3"});
  SequenceOptions kitti_layout;
  kitti_layout.layout = std::string(kKittiLayout);
  fs::create_directories(dir_ / "empty");
  text(dir_ / "empty" / "times.txt", "0\n");
  expect_error<FormatError>([&] { open_sequence((dir_ / "empty").string(), kitti_layout); },
                            {"no image_0", "no image_0..image_3"});
}

TEST_F(LayoutTest, KittiFrameCountMustMatchTimesTxt) {
  const fs::path seq = kitti("00", {0}, 3, 4);
  expect_error<FormatError>(
      [&] { open_sequence(seq.string(), SequenceOptions{}); },
      {(seq / "image_0").string(), "3 images", (seq / "times.txt").string(), "4 timestamps"});
}

TEST_F(LayoutTest, KittiTimesTxtIsRequiredAndParsed) {
  const fs::path seq = kitti("00", {0}, 2, 2);
  text(seq / "times.txt", "0.0\nnot-a-time\n");
  expect_error<FormatError>([&] { open_sequence(seq.string(), SequenceOptions{}); },
                            {"times.txt:2", "not-a-time"});
  fs::remove(seq / "times.txt");
  SequenceOptions kitti_layout;
  kitti_layout.layout = std::string(kKittiLayout);
  expect_error<FormatError>([&] { open_sequence(seq.string(), kitti_layout); },
                            {"no times.txt", "--layout folder"});
  // A times.txt that is not a file is named for what it is, and the folder
  // is still found to be a KITTI sequence (it was "has no times.txt", or,
  // with auto, "no images in folder").
  fs::create_directory(seq / "times.txt");
  for (const SequenceOptions& o : {SequenceOptions{}, kitti_layout}) {
    expect_error<FormatError>([&] { open_sequence(seq.string(), o); }, {"a times.txt that is a folder"});
  }
  fs::remove(seq / "times.txt");
  fs::create_symlink("/dev/zero", seq / "times.txt");
  expect_error<FormatError>([&] { open_sequence(seq.string(), SequenceOptions{}); },
                            {"a times.txt that is not a regular file"});
  fs::remove(seq / "times.txt");
  fs::create_symlink(seq / "nowhere.txt", seq / "times.txt");
  expect_error<FormatError>([&] { open_sequence(seq.string(), SequenceOptions{}); },
                            {"a times.txt that is a broken link"});
  fs::remove(seq / "times.txt");
}

TEST_F(LayoutTest, KittiMissingFrameNumberIsAnError) {
  const fs::path seq = kitti("00", {0}, 4, 3);
  fs::remove(seq / "image_0" / kitti_name(2));  // 000000, 000001, 000003
  expect_error<FormatError>([&] { open_sequence(seq.string(), SequenceOptions{}); },
                            {"frame 2", "000003.png", "expected '000002.png'"});
}

TEST_F(LayoutTest, KittiFlagsOnAnotherLayoutAreRejected) {
  image(dir_ / "f" / "1.png");
  SequenceOptions options;
  options.camera = 1;
  expect_error<InvalidArgument>([&] { open_sequence((dir_ / "f").string(), options); },
                                {"camera", "folder"});
  options.camera = 4;
  expect_error<InvalidArgument>([&] { options.check(); }, {"camera = 4"});
  SequenceOptions bad_number;
  bad_number.kitti_sequence = "0a";
  expect_error<InvalidArgument>([&] { bad_number.check(); }, {"'0a'"});
}

// ---------------------------------------------------------------- FAB-MAP

TEST_F(LayoutTest, FabmapSidesPickAlternatingFiles) {
  const fs::path folder = fabmap(6);
  SequenceOptions options;
  options.layout = std::string(kFabmapLayout);
  EXPECT_EQ(names_of(open_sequence(folder.string(), options)),
            (std::vector<std::string>{"0001.jpg", "0003.jpg", "0005.jpg"}));
  options.side = Side::kRight;
  EXPECT_EQ(names_of(open_sequence(folder.string(), options)),
            (std::vector<std::string>{"0002.jpg", "0004.jpg", "0006.jpg"}));
  options.side = Side::kBoth;
  EXPECT_EQ(open_sequence(folder.string(), options).images.size(), 6u);
  EXPECT_EQ(names_of(open_sequence(folder.string(), options))[3], "0004.jpg");
  // FAB-MAP folders look like any folder: auto never picks fabmap.
  EXPECT_EQ(detect_layout(folder.string()), std::string(kFolderLayout));
}

TEST_F(LayoutTest, FabmapOddImageCountIsAnError) {
  const fs::path folder = fabmap(5);
  for (Side side : {Side::kBoth, Side::kLeft}) {
    SequenceOptions options;
    options.layout = std::string(kFabmapLayout);
    options.side = side;
    expect_error<FormatError>([&] { open_sequence(folder.string(), options); },
                              {folder.string(), "5 images", "odd", "0005.jpg"});
  }
}

TEST_F(LayoutTest, SubsamplingAppliesAfterTheLayout) {
  const fs::path folder = fabmap(12);
  SequenceOptions options;
  options.layout = std::string(kFabmapLayout);
  options.side = Side::kRight;     // 0002, 0004, ..., 0012: six frames
  options.selection = {1, -1, 2};  // frames 1, 3, 5
  EXPECT_EQ(names_of(open_sequence(folder.string(), options)),
            (std::vector<std::string>{"0004.jpg", "0008.jpg", "0012.jpg"}));
  EXPECT_EQ(open_layout(folder.string(), options).images.size(), 6u);
  options.selection = {0, 2, 1};
  EXPECT_EQ(names_of(open_sequence(folder.string(), options)),
            (std::vector<std::string>{"0002.jpg", "0004.jpg", "0006.jpg"}));
  options.selection = {6, -1, 1};
  expect_error<InvalidArgument>([&] { open_sequence(folder.string(), options); },
                                {"first = 6", "6 frames"});
}

}  // namespace
}  // namespace lsgd::io
