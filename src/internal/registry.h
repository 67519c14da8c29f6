// A table of named factories (search modes, verification stages, dataset
// layouts, ground-truth formats): the built-in entries first, then those an
// application registers. Entry has const char* name and summary and a
// function pointer: `make` (modes, stages) or `open` (layouts, formats).
#pragma once

#include <mutex>
#include <string>
#include <vector>

#include "internal/check.h"

namespace lsgd::internal {

// Whether an entry has its function: `make` or `open`, whichever it declares.
template <class Entry>
auto has_function(const Entry& e, int) -> decltype(e.make, bool()) {
  return e.make != nullptr;
}
template <class Entry>
auto has_function(const Entry& e, long) -> decltype(e.open, bool()) {
  return e.open != nullptr;
}

template <class Entry>
class Registry {
 public:
  // `what` names an entry in messages: "search mode", "verification stage".
  Registry(const char* what, std::vector<Entry> builtin) : what_(what), entries_(std::move(builtin)) {}

  std::vector<Entry> entries() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return entries_;
  }

  // InvalidArgument ("<caller>: ...") for an entry without name, summary or
  // function, a name in `reserved`, or one already registered.
  void add(const Entry& entry, const char* caller, const char* reserved = nullptr) {
    if (entry.name == nullptr || *entry.name == '\0' || entry.summary == nullptr ||
        !has_function(entry, 0)) {
      throw_invalid(caller, ": a ", what_, " needs a name, a summary and a function");
    }
    if (reserved != nullptr && std::string(entry.name) == reserved) {
      throw_invalid(caller, ": '", reserved, "' is not a ", what_, " name");
    }
    const std::lock_guard<std::mutex> lock(mutex_);
    for (const Entry& e : entries_) {
      if (std::string(e.name) == entry.name) {
        throw_invalid(caller, ": ", what_, " '", entry.name, "' is already registered");
      }
    }
    entries_.push_back(entry);
  }

  // "a, b, c"
  std::string names() const {
    std::string out;
    for (const Entry& e : entries()) out += (out.empty() ? "" : ", ") + std::string(e.name);
    return out;
  }

  // `first` (when given: "auto") and every entry's name, in registration order.
  std::vector<std::string> name_list(const char* first = nullptr) const {
    std::vector<std::string> out;
    if (first != nullptr) out.emplace_back(first);
    for (const Entry& e : entries()) out.emplace_back(e.name);
    return out;
  }

  // `name` when it is `also` ("auto") or a registered name; InvalidArgument
  // "<what> 'name' is unknown: expected auto, a, b or c" otherwise.
  std::string parse(const std::string& name, const char* also) const {
    const std::vector<std::string> names = name_list(also);
    for (const std::string& n : names) {
      if (n == name) return name;
    }
    std::string all;
    for (std::size_t k = 0; k < names.size(); ++k) {
      all += (k == 0 ? "" : k + 1 == names.size() ? " or " : ", ") + names[k];
    }
    throw_invalid(what_, " '", shown_value(name), "' is unknown: expected ", all);
  }

  // The entry named `name`; InvalidArgument naming it and the registered
  // ones when there is none.
  Entry find(const std::string& name) const {
    for (const Entry& e : entries()) {
      if (name == e.name) return e;
    }
    throw_invalid(what_, " '", shown_value(name), "' is unknown: expected one of ", names());
  }

 private:
  const char* what_;
  mutable std::mutex mutex_;
  std::vector<Entry> entries_;
};

}  // namespace lsgd::internal
