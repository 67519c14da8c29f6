// Options declared once. Every option of the detector is one OptionField in
// the table of its stage (the static fields() of the stage's options struct:
// SegmentationOptions::fields() in segmentation.cc, and so on), with its
// name, unit, range and one line of documentation. From those tables come:
// - validation: each struct's check() runs check_options() on its table
//   (plus the rules that tie two options together);
// - the YAML reader and writer (lsgd::io::parse_config, to_yaml);
// - `--option KEY=VALUE` on the command line (set_option());
// - the database's check on resume (which options may differ, which matter);
// - docs/options.md (`lsgd options --markdown`, checked by a test).
// docs/design.md, "Add an option", is the recipe.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace lsgd {

enum class OptionKind { kInteger, kReal, kChoice };

template <class S>
struct OptionField {
  std::string name;  // key within its table: "min_gap", "nodes.alpha"
  OptionKind kind = OptionKind::kInteger;
  std::string unit;  // "pixels", "frames", "sigma" or empty
  std::string doc;   // one line
  // Numbers: the valid range, [lo, hi] or (lo, hi] when lo_open.
  double lo = 0;
  double hi = 0;
  bool lo_open = false;
  // Integers: what the C++ type holds (values outside are not representable).
  std::int64_t type_min = 0;
  std::int64_t type_max = 0;
  std::function<std::vector<std::string>()> choices;  // kChoice: the accepted names
  bool list = false;  // kChoice: "none" or a comma-separated list of choices
  std::function<std::string(const S&)> text;          // the value as text that reads back equal
  std::function<double(const S&)> number;             // numbers: the value
  std::function<void(S&, std::int64_t)> set_integer;  // kInteger (value within the type)
  std::function<void(S&, double)> set_real;           // kReal
  // kChoice: sets the named value; InvalidArgument for a name it does not accept.
  std::function<void(S&, const std::string&)> set_choice;
  // Whether the value matters under these options (null: always), e.g.
  // search.nodes.* only in nodes mode; a resumed database ignores it otherwise.
  std::function<bool(const S&)> applies;
  std::string when;  // what `applies` tests, for the docs: "in nodes mode"
  // May differ from the stored options when a database is resumed (decision.*).
  bool resumable = false;
};

template <class S>
using OptionTable = std::vector<OptionField<S>>;

// Shortest decimal text that parses back to exactly `value` ("0.1", "3",
// "1e+300"; "inf", "-inf", "nan").
std::string shortest_text(double value);
// The same, always with a '.' or an exponent so that it reads as a real
// (YAML); .inf, -.inf, .nan.
std::string format_real(double value);

// What the option tables' templates below call (and an application's own
// option code may): InvalidArgument naming the key, the value as typed and
// what it must be.
//
// Checks `value` of option `key` against [lo, hi] ((lo, hi] when lo_open),
// "key = value is out of range: must be in [lo, hi] unit"; `text` is the value
// as the message shows it (empty: the number itself).
void check_option_range(const std::string& key, double value, const std::string& text, double lo,
                        double hi, bool lo_open, bool integer, const std::string& unit);
// An integer option's text ("50", "-1") within [lo, hi] (its type's range).
std::int64_t parse_option_integer(const std::string& key, const std::string& text, std::int64_t lo,
                                  std::int64_t hi);
// A real option's text ("0.8", "1e-3", YAML's .inf and .nan).
double parse_option_real(const std::string& key, const std::string& text);
// InvalidArgument "key = 'value' is not one of a, b or c" unless `value` is
// one of `choices`.
void check_option_choice(const std::string& key, const std::string& value,
                         const std::vector<std::string>& choices);

// ---- builders for the tables

template <class S, class T>
OptionField<S> integer_option(const char* name, T S::*member, T lo, T hi, const char* unit,
                              const char* doc) {
  OptionField<S> f;
  f.name = name;
  f.kind = OptionKind::kInteger;
  f.unit = unit;
  f.doc = doc;
  f.lo = static_cast<double>(lo);
  f.hi = static_cast<double>(hi);
  f.type_min = std::numeric_limits<T>::min();
  f.type_max = std::numeric_limits<T>::max();
  f.text = [member](const S& s) { return std::to_string(s.*member); };
  f.number = [member](const S& s) { return static_cast<double>(s.*member); };
  f.set_integer = [member](S& s, std::int64_t v) { s.*member = static_cast<T>(v); };
  return f;
}

template <class S>
OptionField<S> real_option(const char* name, double S::*member, double lo, double hi,
                           bool lo_open, const char* unit, const char* doc) {
  OptionField<S> f;
  f.name = name;
  f.kind = OptionKind::kReal;
  f.unit = unit;
  f.doc = doc;
  f.lo = lo;
  f.hi = hi;
  f.lo_open = lo_open;
  f.text = [member](const S& s) { return format_real(s.*member); };
  f.number = [member](const S& s) { return s.*member; };
  f.set_real = [member](S& s, double v) { s.*member = v; };
  return f;
}

// An enum member: `values` in the order the docs list them, to_string(E) and
// `parse` (const char* -> E, InvalidArgument for an unknown name).
template <class S, class E>
OptionField<S> enum_option(const char* name, E S::*member, std::vector<E> values,
                           E (*parse)(const char*), const char* doc) {
  OptionField<S> f;
  f.name = name;
  f.kind = OptionKind::kChoice;
  f.doc = doc;
  f.choices = [values] {
    std::vector<std::string> names;
    for (const E v : values) names.emplace_back(to_string(v));
    return names;
  };
  f.text = [member](const S& s) { return std::string(to_string(s.*member)); };
  f.set_choice = [member, parse](S& s, const std::string& v) { s.*member = parse(v.c_str()); };
  return f;
}

// Appends the fields of `inner` (the table of member `member`) to `out`
// under "prefix.", applying when `applies` says so (null: always; `when`
// says it in words).
template <class S, class Inner>
void nest(OptionTable<S>& out, const std::string& prefix, Inner S::*member,
          const OptionTable<Inner>& inner, std::function<bool(const S&)> applies = {},
          const std::string& when = "") {
  for (const OptionField<Inner>& f : inner) {
    OptionField<S> g;
    g.name = prefix + "." + f.name;
    g.kind = f.kind;
    g.unit = f.unit;
    g.doc = f.doc;
    g.lo = f.lo;
    g.hi = f.hi;
    g.lo_open = f.lo_open;
    g.type_min = f.type_min;
    g.type_max = f.type_max;
    g.choices = f.choices;
    g.list = f.list;
    g.resumable = f.resumable;
    g.when = applies ? when : f.when;
    if (f.text) g.text = [member, t = f.text](const S& s) { return t(s.*member); };
    if (f.number) g.number = [member, n = f.number](const S& s) { return n(s.*member); };
    if (f.set_integer) g.set_integer = [member, w = f.set_integer](S& s, std::int64_t v) { w(s.*member, v); };
    if (f.set_real) g.set_real = [member, w = f.set_real](S& s, double v) { w(s.*member, v); };
    if (f.set_choice) {
      g.set_choice = [member, w = f.set_choice](S& s, const std::string& v) { w(s.*member, v); };
    }
    if (applies || f.applies) {
      g.applies = [member, outer = applies, own = f.applies](const S& s) {
        return (!outer || outer(s)) && (!own || own(s.*member));
      };
    }
    out.push_back(std::move(g));
  }
}

// ---- options a registered search mode or verification stage brings

// One option of a mode or stage registered from outside the library
// (SearchMode::options, StageType::options). Its key is
// search.<mode>.<name> or verification.<stage>.<name>; from then on it is
// an option like the built-in ones: validated, read from YAML and
// `--option`, listed by `lsgd options` in a program that registered it,
// stored in a database and checked on resume, applying only with its mode
// or stage. docs/design.md, "Add a search mode".
struct OwnOption {
  std::string name;  // lower case letters, digits and '_': "k", "max_depth"
  OptionKind kind = OptionKind::kInteger;
  std::string default_value;  // as text: "4", "0.5", one of `choices`
  double lo = 0;              // numbers: the valid range, [lo, hi] ((lo, hi] when lo_open)
  double hi = 0;
  bool lo_open = false;
  std::vector<std::string> choices;  // kChoice: the accepted names
  std::string unit;                  // "frames", "pixels" or empty
  std::string doc;                   // one line
};

// The values of registered modes' or stages' own options, by key
// ("<mode>.<name>"), as the option table sets them (canonical text); a key
// not set has its declared default.
class OwnOptionValues {
 public:
  // The value set for `key`, or nullptr.
  const std::string* find(const std::string& key) const;
  void set(const std::string& key, std::string text) { values_[key] = std::move(text); }
  bool operator==(const OwnOptionValues& o) const { return values_ == o.values_; }

 private:
  std::map<std::string, std::string> values_;
};

// Throws InvalidArgument ("<caller>: <owner>: ...") unless every declaration
// is complete and its default valid, and returns them with their defaults as
// the table writes them ("0.50" -> "0.5").
std::vector<OwnOption> checked_own_options(const std::vector<OwnOption>& options,
                                           const std::string& caller, const std::string& owner);
// The value of option `name` of mode or stage `owner` in `values` (its
// default when not set), `declared` its declarations; InvalidArgument when
// `owner` declares no such option or it is of another kind.
std::int64_t own_integer(const OwnOptionValues& values, const std::vector<OwnOption>& declared,
                         const std::string& owner, const std::string& name);
double own_real(const OwnOptionValues& values, const std::vector<OwnOption>& declared,
                const std::string& owner, const std::string& name);
std::string own_choice(const OwnOptionValues& values, const std::vector<OwnOption>& declared,
                       const std::string& owner, const std::string& name);

// The table fields of `owner`'s own options in S (whose member `values`
// holds them), applying when `applies` says so (`when` in words).
template <class S>
void add_own_options(OptionTable<S>& out, const std::string& owner,
                     const std::vector<OwnOption>& declared, OwnOptionValues S::*values,
                     std::function<bool(const S&)> applies, const std::string& when) {
  for (const OwnOption& o : declared) {
    OptionField<S> f;
    const std::string key = owner + "." + o.name;
    f.name = key;
    f.kind = o.kind;
    f.unit = o.unit;
    f.doc = o.doc;
    f.lo = o.lo;
    f.hi = o.hi;
    f.lo_open = o.lo_open;
    f.type_min = std::numeric_limits<std::int64_t>::min();
    f.type_max = std::numeric_limits<std::int64_t>::max();
    f.text = [values, key, def = o.default_value](const S& s) {
      const std::string* v = (s.*values).find(key);
      return v != nullptr ? *v : def;
    };
    if (o.kind == OptionKind::kChoice) {
      f.choices = [choices = o.choices] { return choices; };
      f.set_choice = [values, key, choices = o.choices](S& s, const std::string& v) {
        check_option_choice(key, v, choices);
        (s.*values).set(key, v);
      };
    } else {
      f.number = [t = f.text, key](const S& s) { return parse_option_real(key, t(s)); };
      f.set_integer = [values, key](S& s, std::int64_t v) { (s.*values).set(key, std::to_string(v)); };
      f.set_real = [values, key](S& s, double v) { (s.*values).set(key, format_real(v)); };
    }
    f.applies = applies;
    f.when = when;
    out.push_back(std::move(f));
  }
}

// ---- what the tables give

// Checks every number of `s` against its range (InvalidArgument
// "prefix.name = value is out of range: must be in [lo, hi] unit").
template <class S>
void check_options(const OptionTable<S>& table, const S& s, const std::string& prefix) {
  for (const OptionField<S>& f : table) {
    if (f.kind == OptionKind::kChoice) continue;
    const double v = f.number(s);
    if (!((f.lo_open ? v > f.lo : v >= f.lo) && v <= f.hi)) {  // also rejects NaN
      check_option_range(prefix.empty() ? f.name : prefix + "." + f.name, v,
                         f.kind == OptionKind::kReal ? std::string() : f.text(s), f.lo, f.hi,
                         f.lo_open, f.kind == OptionKind::kInteger, f.unit);
    }
  }
}

// Finds `key` in `table`; nullptr when it is not there.
template <class S>
const OptionField<S>* find_option(const OptionTable<S>& table, const std::string& key) {
  for (const OptionField<S>& f : table) {
    if (f.name == key) return &f;
  }
  return nullptr;
}

// Sets option `f` of `s` from text as a user types it ("50", "0.8",
// "nodes"); InvalidArgument naming the key when the text is not a value of
// the option's kind (the range is check()'s).
template <class S>
void set_option_text(const OptionField<S>& f, S& s, const std::string& text) {
  switch (f.kind) {
    case OptionKind::kInteger:
      f.set_integer(s, parse_option_integer(f.name, text, f.type_min, f.type_max));
      return;
    case OptionKind::kReal:
      f.set_real(s, parse_option_real(f.name, text));
      return;
    case OptionKind::kChoice:
      f.set_choice(s, text);
      return;
  }
}

}  // namespace lsgd
