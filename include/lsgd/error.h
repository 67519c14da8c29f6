// Error hierarchy of the lsgd library. Every error a user can cause (bad
// options, bad images, unreadable or malformed files) is reported by throwing
// one of these, with a message that names the file, field or value.
#pragma once

#include <stdexcept>
#include <string>

namespace lsgd {

// Base class: catch this to handle every lsgd error. A NUL in the message
// (a value quoted from a config or a Python str) is written as "\0": what()
// is read up to the first NUL, which cut the rest of the message off.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(visible(message)) {}
  explicit Error(const char* message) : std::runtime_error(message) {}

 private:
  static std::string visible(const std::string& message) {
    if (message.find('\0') == std::string::npos) return message;
    std::string out;
    out.reserve(message.size() + 8);
    for (const char c : message) {
      if (c == '\0') {
        out += "\\0";
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
