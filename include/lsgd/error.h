// Error hierarchy of the lsgd library. Every error a user can cause (bad
// options, bad images, unreadable or malformed files) is reported by throwing
// one of these, with a message that names the file, field or value.
#pragma once

#include <stdexcept>
#include <string>

namespace lsgd {

// Base class: catch this to handle every lsgd error.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
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

// A file was read but its content is malformed (config, ground truth, image).
class FormatError : public Error {
 public:
  using Error::Error;
};

}  // namespace lsgd
