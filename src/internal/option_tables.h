// Option tables that hold what registered search modes and verification
// stages declare (OwnOption, lsgd/options.h): SearchOptions::fields(),
// VerificationOptions::fields() and DetectorOptions::fields() are built
// again after a registration. A table once returned stays alive (a caller
// may hold a reference to it), so each registration keeps one more copy:
// a few kilobytes for each of a handful of registrations.
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>

#include "internal/check.h"
#include "lsgd/options.h"

namespace lsgd::internal {

// How many modes and stages have been registered so far (any thread).
std::uint64_t registrations();
// Called by register_search_mode() and register_verification_stage() once
// the entry is in its registry.
void count_registration();

// The table `build` makes, built again when a registration came after the
// last build.
template <class Table>
const Table& current_table(Table (*build)()) {
  static std::mutex mutex;
  static std::deque<Table> tables;
  static std::uint64_t built_at = 0;
  const std::lock_guard<std::mutex> lock(mutex);
  const std::uint64_t now = registrations();
  if (tables.empty() || built_at != now) {
    tables.push_back(build());
    built_at = now;
  }
  return tables.back();
}

// The choice among a registry's names (search.mode, descriptor.type): the
// names listed when asked (registrations included), a value checked by
// `find` (InvalidArgument naming the registered ones) before it is set.
template <class S, class Entry>
OptionField<S> registry_choice(const char* name, const char* doc, std::vector<Entry> (*entries)(),
                               Entry (*find)(const std::string&), std::string S::*member) {
  OptionField<S> f;
  f.name = name;
  f.kind = OptionKind::kChoice;
  f.doc = doc;
  f.choices = [entries] {
    std::vector<std::string> names;
    for (const Entry& e : entries()) names.emplace_back(e.name);
    return names;
  };
  f.text = [member](const S& s) { return s.*member; };
  f.set_choice = [find, member](S& s, const std::string& value) {
    find(value);
    s.*member = value;
  };
  return f;
}

// A mode or stage entry about to be registered, its own options checked
// (checked_own_options) and their defaults made canonical: `what` ("mode",
// "stage") with options may not be named as an option of S (section
// "search", "verification"), whose keys its options would sit beside.
template <class S, class Entry>
Entry with_checked_options(const Entry& entry, const char* caller, const char* what,
                           const char* section) {
  Entry out = entry;
  if (entry.name == nullptr || entry.options.empty()) return out;
  for (const OptionField<S>& f : S::fields()) {
    if (f.name == entry.name) {
      throw_invalid(caller, ": a ", what, " with options cannot be named '", entry.name,
                    "', an option of ", section);
    }
  }
  out.options = checked_own_options(entry.options, caller, std::string(section) + "." + entry.name);
  return out;
}

}  // namespace lsgd::internal
