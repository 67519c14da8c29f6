// The descriptor seam (issue 36): what a cell's histogram counts is a
// registered descriptor (DescriptorType, lsgd/descriptor.h). The built-in
// "intensity" is the paper's and the fused path; "gradient" counts gradient
// orientations; a descriptor registered from outside the core files
// (docs/design.md, "Add a descriptor", followed here) runs through the same
// detector, brings its own options, and is stored with the map's options, so
// a database or a described frame of another descriptor is refused by name.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "lsgd/descriptor.h"
#include "lsgd/descriptors/gradient.h"
#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/io/config.h"
#include "lsgd/io/database.h"
#include "database_test_support.h"
#include "detector_util.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::frame;
using test::message_of;

// "test-levels": gray levels rounded down to a multiple of its own option
// `step` (1: the intensity descriptor itself).
void levels_codes(const GrayImage& work, const DescriptorOptions& options, GrayImage& codes) {
  const auto step = static_cast<int>(options.own_integer("step"));
  codes = work;
  for (std::uint8_t& v : codes.pixels) v = static_cast<std::uint8_t>(v / step * step);
}

void register_levels() {
  static const bool once = [] {
    const OwnOption step{"step", OptionKind::kInteger, "16", 1, 128, false, {}, "", "gray levels per bin"};
    register_descriptor_type({"test-levels", "gray levels in bins of `step`", levels_codes, {step}});
    return true;
  }();
  (void)once;
}

DetectorOptions with_type(const std::string& type) {
  DetectorOptions o;
  o.search.min_gap = 10;
  set_option(o, "descriptor.type", type);
  return o;
}

TEST(DescriptorTypes, TheRegistryNamesTheBuiltInOnesFirstAndRefusesIncompleteEntries) {
  register_levels();
  const std::vector<DescriptorType> types = descriptor_types();
  ASSERT_GE(types.size(), 3u);
  EXPECT_STREQ(types[0].name, kIntensityDescriptor);
  EXPECT_STREQ(types[1].name, kGradientDescriptor);
  EXPECT_EQ(descriptor_type_names().rfind("intensity, gradient", 0), 0u) << descriptor_type_names();

  EXPECT_THROW(register_descriptor_type({"test-levels", "again", levels_codes}), InvalidArgument);
  EXPECT_THROW(register_descriptor_type({"", "no name", levels_codes}), InvalidArgument);
  EXPECT_THROW(register_descriptor_type({"test-none", "no make", nullptr}), InvalidArgument);
  OwnOption bare;
  bare.name = "k";  // no documentation, no range
  EXPECT_THROW(register_descriptor_type({"test-bare", "incomplete option", levels_codes, {bare}}),
               InvalidArgument);
  OwnOption fine = gradient_options()[0];
  const std::string clash = message_of<InvalidArgument>(
      [&] { register_descriptor_type({"storage", "named as an option", levels_codes, {fine}}); });
  EXPECT_NE(clash.find("'storage'"), std::string::npos) << clash;

  const std::string unknown = message_of<InvalidArgument>([] {
    DetectorOptions o;
    set_option(o, "descriptor.type", "sift");
  });
  EXPECT_NE(unknown.find("sift"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("gradient"), std::string::npos) << unknown;
  DetectorOptions o;
  o.descriptor.type = "sift";  // set directly: the detector's check names it
  const std::string made = message_of<InvalidArgument>([&] { Detector d(o); });
  EXPECT_NE(made.find("descriptor.type"), std::string::npos) << made;
}

// Through the seam (the codes counted after the segmentation) a descriptor
// whose codes are the gray levels gives the fused intensity path's results
// bit for bit: the seam changes nothing but what is counted.
TEST(DescriptorTypes, CodesCountedAfterTheSegmentationEqualTheFusedIntensityPath) {
  register_levels();
  DetectorOptions levels = with_type("test-levels");
  set_option(levels, "descriptor.test-levels.step", "1");
  Detector a(levels), b(with_type(kIntensityDescriptor));
  for (int i = 0; i < 40; ++i) test::expect_same(a.process(frame(i)), b.process(frame(i)));
  for (std::int64_t j = 0; j < 40; ++j) {
    EXPECT_EQ(a.store().view(j).hist[0], b.store().view(j).hist[0]);
    EXPECT_EQ(0, std::memcmp(a.store().view(j).hist, b.store().view(j).hist,
                             sizeof(Bin) * kBins * static_cast<std::size_t>(a.store().view(j).cells)));
  }
  // Its own option reaches it: in bins of 16 levels only every 16th bin is used.
  Detector c(with_type("test-levels"));
  c.process(frame(0));
  const DescriptorView v = c.store().view(0);
  for (int k = 0; k < v.cells * kBins; ++k) {
    if (k % 16 != 0) {
      ASSERT_EQ(v.hist[k], 0) << "bin " << k;
    }
  }
}

TEST(GradientDescriptor, CountsEdgeOrientationsAndLeavesFlatPixelsInBinZero) {
  // A vertical edge: dark left half, bright right half.
  GrayImage image = test::uniform_image(40, 20, 20);
  for (int y = 0; y < 20; ++y) {
    for (int x = 20; x < 40; ++x) image.pixels[static_cast<std::size_t>(y) * 40 + x] = 100;
  }
  DescriptorOptions o;
  o.type = kGradientDescriptor;
  GrayImage codes;
  gradient_codes(image, o, codes);
  ASSERT_EQ(codes.width, 40);
  ASSERT_EQ(codes.height, 20);
  // gx > 0, gy = 0 on the edge: angle 0, bin 16 of 32, code 2 (16 + 1).
  for (int y = 1; y < 19; ++y) {
    EXPECT_EQ(codes.at(19, y), 34) << "y " << y;
    EXPECT_EQ(codes.at(20, y), 34) << "y " << y;
    EXPECT_EQ(codes.at(10, y), 0);
    EXPECT_EQ(codes.at(30, y), 0);
  }
  // The other way round: angle pi, the last bin (clamped), code 64.
  GrayImage mirrored = image;
  for (std::uint8_t& v : mirrored.pixels) v = static_cast<std::uint8_t>(v == 20 ? 100 : 20);
  gradient_codes(mirrored, o, codes);
  EXPECT_EQ(codes.at(20, 5), 64);

  // A uniform frame is flat everywhere; a gain on the frame changes no code.
  gradient_codes(test::uniform_image(16, 16, 77), o, codes);
  EXPECT_TRUE(std::all_of(codes.pixels.begin(), codes.pixels.end(), [](std::uint8_t v) { return v == 0; }));
  GrayImage noisy = test::random_image(64, 48, 7);
  for (std::uint8_t& v : noisy.pixels) v = static_cast<std::uint8_t>(v / 2);
  GrayImage brighter = noisy;
  for (std::uint8_t& v : brighter.pixels) v = static_cast<std::uint8_t>(2 * v);
  GrayImage a, b;
  gradient_codes(noisy, o, a);
  gradient_codes(brighter, o, b);
  EXPECT_EQ(a.pixels, b.pixels);

  // Its options: more orientations use more codes, a higher threshold leaves more flat.
  DetectorOptions d = with_type(kGradientDescriptor);
  set_option(d, "descriptor.gradient.threshold", "3");
  GrayImage strict;
  gradient_codes(noisy, d.descriptor, strict);
  const auto flat = [](const GrayImage& g) { return std::count(g.pixels.begin(), g.pixels.end(), 0); };
  EXPECT_GT(flat(strict), flat(a));
  // Out of range: check() names the key and the range, as for the built-in options.
  DetectorOptions many = d;
  set_option(many, "descriptor.gradient.orientations", "200");
  std::string message = message_of<InvalidArgument>([&] { many.check(); });
  EXPECT_NE(message.find("descriptor.gradient.orientations = 200 is out of range"), std::string::npos)
      << message;
  DetectorOptions none = d;
  set_option(none, "descriptor.gradient.threshold", "0");
  EXPECT_THROW(Detector{none}, InvalidArgument);
  EXPECT_THROW(set_option(d, "descriptor.gradient.orientations", "many"), InvalidArgument);
  // Another descriptor's options do not apply: read, they are refused.
  EXPECT_THROW(DescriptorOptions{}.own_real("threshold"), InvalidArgument);
}

// The gradient descriptor through the detector: a frame under a gain keeps
// its histograms (the intensity descriptor's move), and compact storage
// holds it too.
TEST(GradientDescriptor, RunsInTheDetectorAndIgnoresAGainOnTheFrame) {
  for (const char* storage : {"exact", "compact"}) {
    SCOPED_TRACE(storage);
    DetectorOptions o = with_type(kGradientDescriptor);
    set_option(o, "descriptor.storage", storage);
    Detector d(o);
    cv::Mat half;
    frame(5).convertTo(half, -1, 0.5);
    cv::Mat full;
    half.convertTo(full, -1, 2.0);  // the same frame at twice the gain of `half`
    d.process(half);
    d.process(full);
    Detector i(with_type(kIntensityDescriptor));
    i.process(half);
    i.process(full);
    // Measured: gradient 0.96 (exact) and 0.97 (compact), intensity 0.77.
    EXPECT_GT(d.similarity(0, 1), 0.95);
    EXPECT_LT(i.similarity(0, 1), 0.85);
  }
}

TEST(DescriptorTypes, AreStoredWithTheMapAndAnotherIsRefusedByName) {
  const std::string path = io::database_test_support::temp_path("descriptor_type.db");
  DetectorOptions o = with_type(kGradientDescriptor);
  set_option(o, "descriptor.gradient.orientations", "16");
  {
    io::Database db = io::Database::create(path, o);
    Detector d(o);
    io::database_test_support::run(d, 0, 12, &db);
  }
  const io::Database db = io::Database::open(path, io::Database::Mode::kReadOnly);
  EXPECT_EQ(db.options().descriptor.type, kGradientDescriptor);
  EXPECT_EQ(db.options().descriptor.own_integer("orientations"), 16);
  EXPECT_NO_THROW(db.check_compatible(o));
  std::string message =
      message_of<InvalidArgument>([&] { db.check_compatible(with_type(kIntensityDescriptor)); });
  EXPECT_NE(message.find("descriptor.type = intensity differs from the stored gradient"), std::string::npos)
      << message;
  DetectorOptions other = o;
  set_option(other, "descriptor.gradient.orientations", "32");
  message = message_of<InvalidArgument>([&] { db.check_compatible(other); });
  EXPECT_NE(message.find("descriptor.gradient.orientations = 32 differs from the stored 16"),
            std::string::npos)
      << message;
  Detector restored(db.options());
  db.restore(restored);
  EXPECT_EQ(restored.size(), 12);
  // The next frame as the map that made it would describe it.
  Detector fresh(o);
  for (int i = 0; i < 13; ++i) fresh.process(frame(i));
  restored.process(frame(12));
  EXPECT_EQ(0, std::memcmp(restored.store().view(12).hist, fresh.store().view(12).hist,
                           sizeof(Bin) * kBins * static_cast<std::size_t>(fresh.store().view(12).cells)));

  // A frame described under another descriptor is refused.
  Detector robot(with_type(kIntensityDescriptor));
  const FrameDescription described = robot.describe_frame(frame(13));
  message = message_of<InvalidArgument>([&] { restored.process(described); });
  EXPECT_NE(message.find("describing_options_key"), std::string::npos) << message;
}

TEST(DescriptorTypes, GoThroughYamlAndBack) {
  DetectorOptions o = with_type(kGradientDescriptor);
  set_option(o, "descriptor.gradient.threshold", "2.5");
  const std::string yaml = io::to_yaml(o);
  EXPECT_NE(yaml.find("type: gradient"), std::string::npos) << yaml;
  const DetectorOptions back = io::parse_config(yaml, "descriptor.yaml");
  EXPECT_EQ(back.descriptor.type, kGradientDescriptor);
  EXPECT_EQ(back.descriptor.own_real("threshold"), 2.5);
  EXPECT_EQ(io::to_yaml(back), yaml);
  const std::string message =
      message_of<Error>([] { io::parse_config("descriptor:\n  type: sift\n", "bad.yaml"); });
  EXPECT_NE(message.find("bad.yaml"), std::string::npos) << message;
  EXPECT_NE(message.find("sift"), std::string::npos) << message;
  // The paper's descriptor is still the default, and the defaults' YAML names it.
  EXPECT_EQ(DetectorOptions{}.descriptor.type, kIntensityDescriptor);
}

}  // namespace
}  // namespace lsgd
