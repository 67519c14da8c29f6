// A search mode and a verification stage registered from outside the library
// bring their own options (OwnOption, include/lsgd/options.h), and those are
// options like the built-in ones: in the option table, set by key, checked
// against their range or choices, read from and written to YAML, given to
// the mode's or stage's make function, stored in a database and checked when
// it is resumed (docs/design.md, "Add a search mode" and "Add a verification
// stage", followed from outside the core files).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/io/config.h"
#include "lsgd/io/database.h"
#include "lsgd/search/exhaustive.h"
#include "lsgd/stage.h"
#include "database_test_support.h"
#include "detector_util.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::frame;
using test::message_of;

// "test-stride": exhaustive search that keeps only the candidates whose frame
// is a multiple of its own option `stride`; `order` "oldest" reverses the
// candidates of equal score (a choice, read to show it arrives).
class Stride final : public CandidateSearch {
 public:
  explicit Stride(const SearchOptions& o)
      : inner_(make_exhaustive_search(o)), stride_(o.own_integer("stride")),
        weight_(o.own_real("weight")), order_(o.own_choice("order")) {}
  const char* name() const override { return "test-stride"; }
  bool scores_every_frame() const override { return false; }
  Outcome search(const Query& q, std::vector<Candidate>& out, std::vector<double>& row) override {
    const Outcome outcome = inner_->search(q, out, row);
    out.erase(std::remove_if(out.begin(), out.end(),
                             [this](const Candidate& c) { return c.frame % stride_ != 0; }),
              out.end());
    for (Candidate& c : out) c.score *= weight_;
    return outcome;
  }
  std::int64_t stride() const { return stride_; }
  const std::string& order() const { return order_; }

 private:
  std::unique_ptr<CandidateSearch> inner_;
  std::int64_t stride_;
  double weight_;
  std::string order_;
};

// "test-from": a gate that rejects every candidate older than its own option
// `first_frame`.
class FromFrame final : public VerificationStage {
 public:
  explicit FromFrame(std::int64_t first) : first_(first) {}
  const char* name() const override { return "test-from"; }
  Role role() const override { return Role::kGate; }
  StageCheck check(std::int64_t, const Candidate& c) override {
    const bool kept = c.frame >= first_;
    return {kept, -1, kept ? "recent" : "too old", 0.0, nullptr};
  }

 private:
  std::int64_t first_;
};

std::vector<OwnOption> stride_options() {
  return {
      {"stride", OptionKind::kInteger, "1", 1, 100, false, {}, "frames",
       "only frames that are a multiple of this are candidates"},
      {"weight", OptionKind::kReal, "1.0", 0, 10, true, {}, "", "scales every score"},
      {"order", OptionKind::kChoice, "newest", 0, 0, false, {"newest", "oldest"}, "",
       "which of equal scores comes first"},
  };
}

std::unique_ptr<CandidateSearch> make_stride(const SearchOptions& o) {
  return std::make_unique<Stride>(o);
}

std::unique_ptr<VerificationStage> make_from(const VerificationOptions& o) {
  return std::make_unique<FromFrame>(o.own_integer("test-from", "first_frame"));
}

void register_own() {
  static const bool once = [] {
    register_search_mode({"test-stride", "every stride-th frame", make_stride, nullptr,
                          stride_options()});
    register_verification_stage(
        {"test-from", "candidates from a frame on", make_from,
         {{"first_frame", OptionKind::kInteger, "0", 0, 1e9, false, {}, "frames",
           "candidates before this frame are rejected"}}});
    return true;
  }();
  (void)once;
}

DetectorOptions stride_detector(const std::string& stride) {
  DetectorOptions o;
  o.search.mode = "test-stride";
  o.search.min_gap = 5;
  o.verification.stages = {kTemporalStage};
  set_option(o, "search.test-stride.stride", stride);
  return o;
}

TEST(OwnOptions, AreInTheTableWithTheirKeyDocumentationAndWhenTheyApply) {
  register_own();
  const OptionField<DetectorOptions>* stride = nullptr;
  const OptionField<DetectorOptions>* first = nullptr;
  for (const OptionField<DetectorOptions>& f : DetectorOptions::fields()) {
    if (f.name == "search.test-stride.stride") stride = &f;
    if (f.name == "verification.test-from.first_frame") first = &f;
  }
  ASSERT_NE(stride, nullptr);
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(stride->doc, "only frames that are a multiple of this are candidates");
  EXPECT_EQ(stride->unit, "frames");
  EXPECT_EQ(stride->when, "in test-stride mode");
  EXPECT_EQ(first->when, "with the test-from stage");
  DetectorOptions o;
  EXPECT_FALSE(stride->applies(o));  // exhaustive mode
  EXPECT_FALSE(first->applies(o));
  o.search.mode = "test-stride";
  parse_verification_stages("temporal,test-from", o.verification);
  EXPECT_TRUE(stride->applies(o));
  EXPECT_TRUE(first->applies(o));
  // The declared defaults, as the table writes them.
  EXPECT_EQ(option_text(o, "search.test-stride.stride"), "1");
  EXPECT_EQ(option_text(o, "search.test-stride.weight"), "1.0");
  EXPECT_EQ(option_text(o, "search.test-stride.order"), "newest");
  EXPECT_EQ(o.search.own_integer("stride"), 1);
  EXPECT_EQ(o.verification.own_integer("test-from", "first_frame"), 0);
}

TEST(OwnOptions, AreSetCheckedAndRefusedByKeyLikeTheBuiltInOnes) {
  register_own();
  DetectorOptions o = stride_detector("3");
  EXPECT_EQ(o.search.own_integer("stride"), 3);
  set_option(o, "search.test-stride.weight", "0.5");
  EXPECT_EQ(o.search.own_real("weight"), 0.5);
  set_option(o, "search.test-stride.order", "oldest");
  EXPECT_EQ(o.search.own_choice("order"), "oldest");
  EXPECT_NO_THROW(o.check());

  // Out of range: check() names the key and the range.
  DetectorOptions bad = stride_detector("0");
  std::string message = message_of<InvalidArgument>([&] { bad.check(); });
  EXPECT_NE(message.find("search.test-stride.stride = 0 is out of range: must be in [1, 100] frames"),
            std::string::npos)
      << message;
  EXPECT_THROW(Detector{bad}, InvalidArgument);
  // Not a number, not a choice, not an option.
  EXPECT_THROW(set_option(o, "search.test-stride.stride", "two"), InvalidArgument);
  message = message_of<InvalidArgument>([&] { set_option(o, "search.test-stride.order", "sideways"); });
  EXPECT_NE(message.find("'sideways' is not one of newest or oldest"), std::string::npos) << message;
  message = message_of<InvalidArgument>([&] { set_option(o, "search.test-stride.strid", "2"); });
  EXPECT_NE(message.find("did you mean 'search.test-stride.stride'"), std::string::npos) << message;
  // A mode reads only what it declares, of the kind declared.
  EXPECT_THROW(o.search.own_integer("nope"), InvalidArgument);
  EXPECT_THROW(o.search.own_real("stride"), InvalidArgument);
  EXPECT_THROW(o.verification.own_integer("no-such-stage", "x"), InvalidArgument);
}

TEST(OwnOptions, GoThroughYamlAndBack) {
  register_own();
  DetectorOptions o = stride_detector("4");
  set_option(o, "search.test-stride.weight", "2.5");
  parse_verification_stages("temporal,test-from", o.verification);
  set_option(o, "verification.test-from.first_frame", "7");
  const std::string yaml = io::to_yaml(o);
  EXPECT_NE(yaml.find("test-stride:"), std::string::npos) << yaml;
  const DetectorOptions back = io::parse_config(yaml, "own.yaml");
  EXPECT_EQ(back.search.own_integer("stride"), 4);
  EXPECT_EQ(back.search.own_real("weight"), 2.5);
  EXPECT_EQ(back.verification.own_integer("test-from", "first_frame"), 7);
  EXPECT_EQ(io::to_yaml(back), yaml);
  // Nested YAML as a user writes it, and its errors name the file and key.
  const DetectorOptions typed = io::parse_config(
      "search:\n  mode: test-stride\n  test-stride:\n    stride: 6\n    order: oldest\n", "typed.yaml");
  EXPECT_EQ(typed.search.own_integer("stride"), 6);
  EXPECT_EQ(typed.search.own_choice("order"), "oldest");
  const std::string message = message_of<InvalidArgument>([] {
    io::parse_config("search:\n  mode: test-stride\n  test-stride:\n    stride: 101\n", "bad.yaml");
  });
  EXPECT_NE(message.find("bad.yaml"), std::string::npos) << message;
  EXPECT_NE(message.find("search.test-stride.stride"), std::string::npos) << message;
}

TEST(OwnOptions, ReachTheModeAndTheStageTheyBelongTo) {
  register_own();
  for (const char* stride : {"1", "3"}) {
    SCOPED_TRACE(stride);
    DetectorOptions o = stride_detector(stride);
    o.verification.stages.clear();  // the search's candidates as they are (no realignment)
    Detector d(o);
    ASSERT_EQ(dynamic_cast<const Stride*>(&d.search())->stride(), std::stoi(stride));
    int candidates = 0;
    for (int i = 0; i < 40; ++i) {
      const Result r = d.process(frame(i));
      for (const Candidate& c : r.candidates) {
        EXPECT_EQ(c.frame % std::stoi(stride), 0) << c.frame;
        ++candidates;
      }
    }
    EXPECT_GT(candidates, 20);
  }
  DetectorOptions gated = stride_detector("1");
  parse_verification_stages("temporal,test-from", gated.verification);
  set_option(gated, "verification.test-from.first_frame", "12");
  Detector d(gated);
  int rejected = 0;
  for (int i = 0; i < 40; ++i) {
    for (const StageVerdict& v : d.process(frame(i)).verification) {
      if (v.stage != "test-from") continue;
      EXPECT_EQ(v.accepted, v.candidate >= 12) << v.candidate;
      rejected += v.accepted ? 0 : 1;
    }
  }
  EXPECT_GT(rejected, 0);
}

TEST(OwnOptions, AreStoredInTheDatabaseAndCheckedOnResume) {
  register_own();
  const std::string path = io::database_test_support::temp_path("own.db");
  DetectorOptions o = stride_detector("3");
  {
    io::Database db = io::Database::create(path, o);
    Detector d(o);
    io::database_test_support::run(d, 0, 12, &db);
  }
  const io::Database db = io::Database::open(path, io::Database::Mode::kReadOnly);
  EXPECT_EQ(db.options().search.own_integer("stride"), 3);
  EXPECT_NO_THROW(db.check_compatible(o));
  const DetectorOptions other = stride_detector("2");
  const std::string message = message_of<InvalidArgument>([&] { db.check_compatible(other); });
  EXPECT_NE(message.find("search.test-stride.stride = 2 differs from the stored 3"), std::string::npos)
      << message;
  Detector restored(db.options());
  db.restore(restored);
  EXPECT_EQ(restored.size(), 12);
  EXPECT_EQ(dynamic_cast<const Stride*>(&restored.search())->stride(), 3);
}

TEST(OwnOptions, IncompleteDeclarationsAreRefusedAtRegistration) {
  register_own();
  const auto mode = [](const char* name, std::vector<OwnOption> options) {
    return SearchMode{name, "a mode", make_stride, nullptr, std::move(options)};
  };
  const auto refused = [&](const char* name, std::vector<OwnOption> options, const char* expected) {
    const std::string message =
        message_of<InvalidArgument>([&] { register_search_mode(mode(name, std::move(options))); });
    EXPECT_NE(message.find(expected), std::string::npos) << message;
  };
  const OwnOption good{"k", OptionKind::kInteger, "2", 1, 9, false, {}, "", "a number"};
  OwnOption o = good;
  o.name = "K";
  refused("test-bad-1", {o}, "option name 'K' must be");
  o = good;
  o.name = "a.b";
  refused("test-bad-2", {o}, "option name 'a.b' must be");
  refused("test-bad-3", {good, good}, "declares 'k' twice");
  o = good;
  o.doc.clear();
  refused("test-bad-4", {o}, "search.test-bad-4.k needs a line of documentation");
  o = good;
  o.default_value = "10";
  refused("test-bad-5", {o}, "the default of search.test-bad-5.k = 10 is out of range");
  o = good;
  o.lo = 5, o.hi = 1;
  refused("test-bad-6", {o}, "has an empty range");
  o = {"c", OptionKind::kChoice, "x", 0, 0, false, {"a", "b"}, "", "a choice"};
  refused("test-bad-7", {o}, "is not one of a or b");
  o.choices.clear();
  refused("test-bad-8", {o}, "needs its choices");
  refused("top_n", {good}, "cannot be named 'top_n', an option of search");
  const std::string message = message_of<InvalidArgument>([&] {
    register_verification_stage({"stages", "a stage", make_from, {good}});
  });
  EXPECT_NE(message.find("cannot be named 'stages'"), std::string::npos) << message;
  // Nothing refused was registered.
  EXPECT_EQ(search_mode_names().find("test-bad"), std::string::npos);
  // The default's text is written as the table writes it.
  o = {"w", OptionKind::kReal, "0.50", 0, 1, false, {}, "", "a real"};
  register_search_mode(mode("test-canonical", {o}));
  DetectorOptions d;
  d.search.mode = "test-canonical";
  EXPECT_EQ(option_text(d, "search.test-canonical.w"), "0.5");
}

}  // namespace
}  // namespace lsgd
