// Error hierarchy of the lsgd library. Every error a user can cause (bad
// options, bad images, unreadable or malformed files) is reported by throwing
// one of these, with a message that names the file, field or value.
#pragma once

#include <stdexcept>
#include <string>

namespace lsgd {

// Base class: catch this to handle every lsgd error. A message is one line:
// a control character in it (a value quoted from a config or a Python str, a
// file name with a newline) is written escaped, NUL as "\0" (what() is read
// up to the first NUL, which cut the rest off), the others as "\xHH" (a
// newline forged "lsgd: note:" lines, an escape sequence reached the
// terminal).
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(visible(message)) {}
  explicit Error(const char* message) : std::runtime_error(visible(message)) {}

 private:
  static bool control(char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7F; }
  static std::string visible(const std::string& message) {
    bool plain = true;
    for (const char c : message) plain = plain && !control(c);
    if (plain) return message;
    std::string out;
    out.reserve(message.size() + 8);
    for (const char c : message) {
      if (c == '\0') {
        out += "\\0";
      } else if (control(c)) {
        const auto u = static_cast<unsigned char>(c);
        out += "\\x";
        out += "0123456789abcdef"[u >> 4];
        out += "0123456789abcdef"[u & 15];
      } else {
        out += c;
      }
    }
    return out;
  }
};

// A value given by the caller is out of range or inconsistent
// (options, image sizes and formats, indices).
class InvalidArgument : public Error {
 public:
  using Error::Error;
};

// A file or folder could not be opened, read or written.
class IoError : public Error {
 public:
  using Error::Error;
};

// The system ran out of something the work needs (file descriptors,
// memory for a read): not the input's fault, so a run stops there instead of
// skipping the input as a bad frame.
class ResourceError : public IoError {
 public:
  using IoError::IoError;
};

// A file was read but its content is malformed (config, ground truth, image).
class FormatError : public Error {
 public:
  using Error::Error;
};

}  // namespace lsgd
