// Sweep grids (parsing, exact ranges, cross-product order, validation) and
// dataset specs; `lsgd sweep` end to end: sweep_cli_test.cc.
#include "lsgd/eval/sweep.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "lsgd/error.h"
#include "lsgd/eval/groundtruth.h"
#include "lsgd/io/config.h"
#include "test_util.h"

namespace fs = std::filesystem;
using lsgd::InvalidArgument;
using lsgd::eval::expand_sweep;
using lsgd::eval::parse_dataset_spec;
using lsgd::eval::parse_sweep_axis;
using lsgd::eval::SweepAxis;
using lsgd::test::message_of;
using Strings = std::vector<std::string>;

namespace {

// ---------------------------------------------------------------- axes

TEST(SweepAxis, CommaList) {
  const SweepAxis a = parse_sweep_axis("search.mode=exhaustive, nodes");
  EXPECT_EQ(a.key, "search.mode");
  EXPECT_EQ(a.values, (Strings{"exhaustive", "nodes"}));
  EXPECT_EQ(a.spec, "search.mode=exhaustive, nodes");
}

TEST(SweepAxis, IntegerRangeIsInclusive) {
  EXPECT_EQ(parse_sweep_axis("segmentation.superpixel_size=10:100:10").values,
            (Strings{"10", "20", "30", "40", "50", "60", "70", "80", "90", "100"}));
  EXPECT_EQ(parse_sweep_axis("k=10:95:10").values.back(), "90");  // the end is not on the grid
  EXPECT_EQ(parse_sweep_axis("k=5:5:1").values, (Strings{"5"}));
  EXPECT_EQ(parse_sweep_axis("k=-1:1:1").values, (Strings{"-1", "0", "1"}));
}

TEST(SweepAxis, FloatRangeDoesNotDrift) {
  EXPECT_EQ(parse_sweep_axis("search.nodes.beta=0.9:1.1:0.1").values,
            (Strings{"0.9", "1.0", "1.1"}));
  // 3 * 0.1 > 0.3 in binary floating point: a naive loop would drop the end.
  EXPECT_EQ(parse_sweep_axis("k=0:0.3:0.1").values, (Strings{"0.0", "0.1", "0.2", "0.3"}));
  const Strings many = parse_sweep_axis("k=0:1:0.01").values;
  ASSERT_EQ(many.size(), 101u);
  EXPECT_EQ(many[29], "0.29");
  EXPECT_EQ(many.back(), "1.00");
  EXPECT_EQ(parse_sweep_axis("k=1:0:-0.25").values,
            (Strings{"1.00", "0.75", "0.50", "0.25", "0.00"}));
  EXPECT_EQ(parse_sweep_axis("k=-0.5:0.5:.5").values, (Strings{"-0.5", "0.0", "0.5"}));
}

TEST(SweepAxis, ItemsMayMixRangesAndValues) {
  EXPECT_EQ(parse_sweep_axis("k=10:30:10,100").values, (Strings{"10", "20", "30", "100"}));
}

TEST(SweepAxis, SemicolonSeparatesItemsHoldingCommas) {
  EXPECT_EQ(parse_sweep_axis("verification.stages=none;temporal,geometric").values,
            (Strings{"none", "temporal,geometric"}));
}

TEST(SweepAxis, BadSpecsNameTheSpec) {
  for (const char* spec :
       {"search.mode", "=1", "a..b=1", "a.b c=1", "k=", "k=1,,2", "k=1 2", "k=a:b:c", "k=1:2",
        "k=1:2:3:4", "k=1:2:0", "k=1:0:1", "k=0:1:-1", "k=0:1e6:1", "k=0:100000:1", "k=x:y",
        "k={a: 1}", "k=1#2", "k=0.1234567891:1:1"}) {
    const std::string message = message_of<InvalidArgument>([&] { parse_sweep_axis(spec); });
    EXPECT_NE(message.find(std::string("'") + spec + "'"), std::string::npos)
        << spec << " -> " << message;
  }
}

// ---------------------------------------------------------------- grids

TEST(SweepGrid, CrossProductInTheOrderGiven) {
  const auto points = expand_sweep({parse_sweep_axis("segmentation.superpixel_size=30,40"),
                                    parse_sweep_axis("search.mode=exhaustive,nodes")},
                                   {});
  ASSERT_EQ(points.size(), 4u);
  const Strings expected[] = {
      {"30", "exhaustive"}, {"30", "nodes"}, {"40", "exhaustive"}, {"40", "nodes"}};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(points[i].values, expected[i]) << i;
    EXPECT_EQ(points[i].options.segmentation.superpixel_size, i < 2 ? 30 : 40) << i;
    EXPECT_EQ(points[i].options.search.mode,
              i % 2 ? lsgd::kNodesSearch : lsgd::kExhaustiveSearch)
        << i;
  }
}

TEST(SweepGrid, ThreeAxesTurnLikeNestedLoops) {
  const auto points = expand_sweep(
      {parse_sweep_axis("search.top_n=1,2"), parse_sweep_axis("search.mode=exhaustive,nodes"),
       parse_sweep_axis("search.nodes.beta=0.9:1.1:0.1")},
      {});
  ASSERT_EQ(points.size(), 12u);
  EXPECT_EQ(points[0].values, (Strings{"1", "exhaustive", "0.9"}));
  EXPECT_EQ(points[2].values, (Strings{"1", "exhaustive", "1.1"}));
  EXPECT_EQ(points[3].values, (Strings{"1", "nodes", "0.9"}));
  EXPECT_EQ(points[11].values, (Strings{"2", "nodes", "1.1"}));
  EXPECT_EQ(points[11].options.search.nodes.beta, 1.1);  // the double nearest 1.1, exactly
  EXPECT_EQ(points[4].options.search.nodes.beta, 1.0);
}

TEST(SweepGrid, ValuesApplyOnTopOfTheBase) {
  lsgd::DetectorOptions base;
  base.segmentation.superpixel_size = 25;
  lsgd::parse_verification_stages("none", base.verification);
  base.search.nodes.alpha = 0.5;
  base.search.mode = "nodes";  // where search.nodes.beta applies
  const auto points = expand_sweep({parse_sweep_axis("search.nodes.beta=0.8")}, base);
  ASSERT_EQ(points.size(), 1u);
  lsgd::DetectorOptions expected = base;
  expected.search.nodes.beta = 0.8;
  EXPECT_EQ(lsgd::io::to_yaml(points[0].options), lsgd::io::to_yaml(expected));
}

// An option that applies in no configuration of the grid gave identical
// rows read as "it does not matter": refused, saying when it applies; one
// that applies in some configurations is swept.
TEST(SweepGrid, AnOptionThatAppliesNowhereIsRefused) {
  for (const auto& [spec, when] : std::vector<std::pair<std::string, std::string>>{
           {"search.nodes.beta=0.5,1.5", "in nodes mode"},
           {"descriptor.gradient.threshold=0.5,5", "with the gradient descriptor"}}) {
    const std::string m = message_of<InvalidArgument>([&] { expand_sweep({parse_sweep_axis(spec)}, {}); });
    EXPECT_NE(m.find("has no effect in any configuration of the grid (it applies " + when + ")"),
              std::string::npos) << m;
  }
  EXPECT_EQ(expand_sweep({parse_sweep_axis("search.nodes.beta=0.5,1.5"),
                          parse_sweep_axis("search.mode=exhaustive,nodes")}, {}).size(), 4u);
}

// A value given twice, or two spellings of one value, ran the same
// configuration twice and printed identical rows (issue 35, seventh pass).
TEST(SweepGrid, AValueGivenTwiceIsRefused) {
  for (const std::string spec : {"decision.threshold=5,5", "decision.threshold=5,5.0",
                                 "decision.threshold=4:6:1,5", "search.mode=index,nodes,index"}) {
    const std::string m = message_of<InvalidArgument>([&] { expand_sweep({parse_sweep_axis(spec)}, {}); });
    EXPECT_NE(m.find("(the same configuration twice, identical rows): give each value once"),
              std::string::npos) << m;
    EXPECT_NE(m.find("sweep '" + spec + "'"), std::string::npos) << m;
  }
  EXPECT_EQ(expand_sweep({parse_sweep_axis("decision.threshold=5,5.5")}, {}).size(), 2u);
}

TEST(SweepGrid, NoAxesIsTheBase) {
  lsgd::DetectorOptions base;
  base.segmentation.superpixel_size = 17;
  const auto points = expand_sweep({}, base);
  ASSERT_EQ(points.size(), 1u);
  EXPECT_TRUE(points[0].values.empty());
  EXPECT_EQ(lsgd::io::to_yaml(points[0].options), lsgd::io::to_yaml(base));
}

TEST(SweepGrid, BadKeysAndValuesNameTheSpec) {
  struct Case {
    const char* spec;
    const char* detail;  // also in the message
  };
  for (const Case& c : {Case{"segmentation.superpixel_sze=30,40", "superpixel_sze"},
                        Case{"segmentation.superpixel_size=1,40", "out of range"},
                        Case{"segmentation.superpixel_size=3.5", "integer"},
                        Case{"search.mode=exhaustive,bogus", "bogus"},
                        Case{"search.nodes=1", "map"}, Case{"nothing.at_all=1", "nothing"},
                        Case{"verification.stages=none;temporal,bogus", "bogus"}}) {
    const std::string message = message_of<InvalidArgument>([&] {
      expand_sweep({parse_sweep_axis("search.top_n=5"), parse_sweep_axis(c.spec)}, {});
    });
    EXPECT_NE(message.find(std::string("'") + c.spec + "'"), std::string::npos)
        << c.spec << " -> " << message;
    EXPECT_NE(message.find(c.detail), std::string::npos) << c.spec << " -> " << message;
    EXPECT_EQ(message.find("(line "), std::string::npos) << message;  // no line of hidden YAML
  }
}

// Each dataset has its own window (sweep_cells sets it): a swept one would be
// dropped without a word, so it is refused naming the spec.
TEST(SweepGrid, TheWindowIsNotSwept) {
  const std::string message =
      message_of<InvalidArgument>([] { expand_sweep({parse_sweep_axis("search.min_gap=5,10")}, {}); });
  EXPECT_NE(message.find("sweep 'search.min_gap=5,10': the window is set per dataset"), std::string::npos)
      << message;
}

// The same for a window in the options the grid is applied on (Python's
// lsgd.sweep(options=...), a --config).
TEST(SweepGrid, AWindowInTheOptionsIsRefused) {
  lsgd::DetectorOptions base;
  base.search.min_gap = 3;
  const std::string message = message_of<InvalidArgument>([&] { expand_sweep({}, base); });
  EXPECT_NE(message.find("the sweep's options set search.min_gap = 3: the window is set per dataset"),
            std::string::npos)
      << message;
}

TEST(SweepGrid, KeySweptTwiceIsAnError) {
  const std::string message = message_of<InvalidArgument>([] {
    expand_sweep({parse_sweep_axis("search.top_n=1"), parse_sweep_axis("search.top_n=2")}, {});
  });
  EXPECT_NE(message.find("already swept"), std::string::npos) << message;
}

// A grid of more than 10,000 configurations is refused before any point is
// parsed (a million took minutes and gigabytes before the first run); 10,000
// are built.
TEST(SweepGrid, MoreThanTenThousandPointsAreRefusedAtOnce) {
  const std::string message = message_of<InvalidArgument>([] {
    expand_sweep({parse_sweep_axis("segmentation.superpixel_size=10:109:1"),
                  parse_sweep_axis("decision.threshold=1:100:1"), parse_sweep_axis("search.top_n=1:100:1")},
                 {});
  });
  EXPECT_NE(message.find("sweep: 1000000 configurations, more than the 10000 a sweep runs"), std::string::npos)
      << message;
  // A grid far beyond 2^64 points is named too.
  std::vector<SweepAxis> huge;
  for (const char* key : {"decision.threshold", "decision.geometric_bonus", "decision.continuity_bonus",
                          "decision.strong_bonus", "decision.track_bonus", "decision.continuity_min_z"}) {
    huge.push_back(parse_sweep_axis(std::string(key) + "=1:10000:1"));
  }
  EXPECT_NE(message_of<InvalidArgument>([&] { expand_sweep(huge, {}); }).find("sweep: 1e+24 configurations"),
            std::string::npos);
  EXPECT_EQ(expand_sweep({parse_sweep_axis("decision.threshold=1:100:1"), parse_sweep_axis("search.top_n=1:100:1")},
                         {})
                .size(),
            10000u);
}

TEST(SweepGrid, YamlMergesSectionsSharingAPrefix) {
  EXPECT_EQ(lsgd::eval::sweep_yaml({"search.mode", "segmentation.superpixel_size",
                                    "search.nodes.beta", "search.nodes.alpha"},
                                   {"nodes", "30", "0.9", "0.7"}),
            "search:\n"
            "  mode: nodes\n"
            "  nodes:\n"
            "    beta: 0.9\n"
            "    alpha: 0.7\n"
            "segmentation:\n"
            "  superpixel_size: 30\n");
  EXPECT_THROW(lsgd::eval::sweep_yaml({"search.nodes", "search.nodes.beta"}, {"1", "2"}),
               InvalidArgument);
  EXPECT_THROW(lsgd::eval::sweep_yaml({"search.mode"}, {"a: b"}), InvalidArgument);
}

// ---------------------------------------------------------------- datasets

TEST(SweepDataset, BothForms) {
  const auto full = parse_dataset_spec("corridor=/d/seq.txt,/d/gt.txt,50");
  EXPECT_EQ(full.name, "corridor");
  EXPECT_EQ(full.sequence, "/d/seq.txt");
  EXPECT_EQ(full.ground_truth, "/d/gt.txt");
  EXPECT_EQ(full.min_gap, 50);
  const auto dir = parse_dataset_spec("nordland-trimmed=/data/nordland,100");
  EXPECT_EQ(dir.name, "nordland-trimmed");
  EXPECT_EQ(dir.sequence, "/data/nordland/sequence.txt");
  EXPECT_EQ(dir.ground_truth, "/data/nordland/groundtruth.txt");
  EXPECT_EQ(dir.min_gap, 100);
}

TEST(SweepDataset, BadSpecsNameTheSpec) {
  for (const char* spec :
       {"/d/seq.txt,/d/gt.txt,50", "=/d,50", "a b=/d,50", "a|b=/d,50", "x=/d", "x=/d,/g,/h,50",
        "x=/d,-1", "x=/d,5.5", "x=/d,fifty", "x=,/g,50", "x=/d,"}) {
    const std::string message = message_of<InvalidArgument>([&] { parse_dataset_spec(spec); });
    EXPECT_NE(message.find(std::string("'") + spec + "'"), std::string::npos)
        << spec << " -> " << message;
  }
}

// A dataset option given twice kept the last without a word.
TEST(SweepDataset, AnOptionGivenTwiceIsRefused) {
  const std::string message =
      message_of<InvalidArgument>([] { parse_dataset_spec("c=/d,50,every=2,every=3"); });
  EXPECT_NE(message.find("every is given twice: give it once"), std::string::npos) << message;
}

// Dataset options after the parts: lsgd eval's layout and ground-truth flags.
TEST(SweepDataset, OptionsAfterThePartsAreEvalsDatasetFlags) {
  const auto k = parse_dataset_spec(
      "kitti05=/kitti,/poses/05.txt,100,layout=kitti,kitti-sequence=5,camera=2,gt-format=kitti-poses,"
      "first=10,every=2,subsample-match=block");
  EXPECT_EQ(k.sequence, "/kitti");
  EXPECT_EQ(k.ground_truth, "/poses/05.txt");
  EXPECT_EQ(k.min_gap, 100);
  EXPECT_EQ(k.sequence_options.layout, lsgd::io::kKittiLayout);
  EXPECT_EQ(k.sequence_options.kitti_sequence, "5");
  EXPECT_EQ(k.sequence_options.camera, 2);
  EXPECT_EQ(k.sequence_options.selection.first, 10);
  EXPECT_EQ(k.sequence_options.selection.every, 2);
  EXPECT_EQ(k.gt_options.format, std::string(lsgd::eval::kKittiPosesGtFormat));
  EXPECT_EQ(k.gt_options.match, lsgd::eval::SubsampleMatch::kBlock);
  const auto f = parse_dataset_spec("cc=/cc,20,layout=fabmap,side=both,gt-rows=image");
  EXPECT_EQ(f.sequence, "/cc/sequence.txt");
  EXPECT_EQ(f.sequence_options.side, lsgd::io::Side::kBoth);
  EXPECT_EQ(f.gt_options.rows, lsgd::eval::GtRows::kImage);
  for (const char* spec : {"x=/d,50,every=0", "x=/d,50,colour=2", "x=/d,50,every=two",
                           "x=/d,50,layout=tree", "x=/d,50,gt-format=csv", "x=/d,50,every=2,/g",
                           "x=/d,50,=3"}) {
    const std::string message = message_of<InvalidArgument>([&] { parse_dataset_spec(spec); });
    EXPECT_NE(message.find(std::string("'") + spec + "'"), std::string::npos)
        << spec << " -> " << message;
  }
}

}  // namespace
