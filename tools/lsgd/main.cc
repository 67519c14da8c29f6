// lsgd: the command-line front end of the LSGDDN-LCD loop-closure detector.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <new>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>

#include "commands.h"
#include "common.h"
#include "internal/check.h"
#include "internal/names.h"
#include "internal/numbers.h"
#include "lsgd/error.h"
#include "lsgd/io/files.h"

namespace {

using lsgd::internal::nearest;
using lsgd::internal::shown_value;

// The subcommand the arguments selected, deepest first ("gt convert"); the
// app itself when none was.
CLI::App* selected(CLI::App& app) {
  CLI::App* at = &app;
  while (!at->get_subcommands().empty()) at = at->get_subcommands().front();
  return at;
}

std::string path_of(const CLI::App* cmd) {
  std::string path;
  for (const CLI::App* at = cmd; at != nullptr; at = at->get_parent()) {
    path = (at->get_parent() == nullptr ? std::string("lsgd") : at->get_name()) + (path.empty() ? "" : " " + path);
  }
  return path;
}

// Help shows every default, but not the sentinels that mean "not given"
// (-1, an empty list): those options' descriptions say what not giving them does.
void hide_sentinel_defaults(CLI::App& app) {
  for (CLI::Option* o : app.get_options()) {
    if (o->get_default_str() == "-1" || o->get_default_str() == "[]") o->default_str("");
  }
  for (CLI::App* sub : app.get_subcommands({})) hide_sentinel_defaults(*sub);
}

// CLI11 converts an integer with strtoll(text, base 0) and a real with
// strtod: an integer beyond 64 bits was read as the largest one (--seed
// 99999999999999999999999 ran seed 18446744073709551615, and --min-gap's
// message named a value nobody typed), a leading 0 made the number octal
// (--first 010 kept frame 8 onwards, the frame 000010.png names; 08 was
// "not in range"), 0x10 was 16, ' 5' was 5 but '5 ' an error, and
// --threshold 1e400 was refused as "inf". Every number flag is read as
// --option and a config read it (internal::parse_number: decimal, one
// optional '+', nothing around it) before CLI11 converts it, and handed
// on in its plain decimal spelling.
CLI::Validator number_as_typed(const std::string& type) {
  return CLI::Validator(
      [type](std::string& text) -> std::string {
        if (text.empty()) return {};  // refuse_empty_values says so
        if (type == "FLOAT") {
          double v = 0;
          const std::errc ec = lsgd::internal::parse_number(text, v);
          if (ec == std::errc::result_out_of_range) {
            return "value " + shown_value(text) + " is out of range: beyond what a double holds";
          }
          return ec == std::errc() ? std::string()
                                   : "'" + shown_value(text) + "' is not a number (decimal, as 7, 2.5 or 1e-3)";
        }
        const std::size_t sign = text[0] == '-' || text[0] == '+' ? 1 : 0;
        if (text.size() == sign || text.find_first_not_of("0123456789", sign) != std::string::npos) {
          // What strtoll would read, but not as decimal digits: refused here.
          // Any other text is left to the flag's own check or to CLI11's
          // conversion error ("'1e3' is not a frame count from 1 to ...").
          const bool hex = text.size() > sign + 1 && text[sign] == '0' && (text[sign + 1] | 0x20) == 'x';
          if (hex || text.find_first_of(" \t\n\v\f\r") != std::string::npos) {
            return "'" + shown_value(text) + "' is not a decimal integer (digits, as 12 or -3)";
          }
          return {};
        }
        // `UINT`: a negative value would wrap around (--seed -5 ran seed
        // 18446744073709551611).
        if (type == "UINT" && text[0] == '-' && text.find_first_not_of('0', 1) != std::string::npos) {
          return "value " + text + " is out of range: must be 0 or more";
        }
        std::int64_t i = 0;
        std::uint64_t u = 0;
        if (lsgd::internal::parses_as(text, i)) {
          text = std::to_string(i);  // no leading zeros: CLI11 would read them as octal
        } else if (text[0] != '-' && lsgd::internal::parses_as(text, u)) {
          text = std::to_string(u);
        } else {
          return "value " + text + " is out of range: far beyond the values it takes";
        }
        return {};
      },
      "", "a decimal number");
}

// Every number flag gets number_as_typed first, before the flag's own checks.
void read_numbers_as_typed(CLI::App& app) {
  for (CLI::Option* o : app.get_options()) {
    const std::string type = o->get_type_name();
    if (type == "INT" || type == "UINT" || type == "FLOAT") o->transform(number_as_typed(type));
  }
  for (CLI::App* sub : app.get_subcommands({})) read_numbers_as_typed(*sub);
}

// An empty value ('' in a shell, often an unset variable) names no file and
// no number: refused, where CLI11 read it as 0 (`eval --min-gap ''`
// scored with min gap 0) or as the default.
void refuse_empty_values(CLI::App& app) {
  const CLI::Validator nonempty(
      [](std::string& text) -> std::string {
        return text.empty() ? "an empty value: give one, or leave the flag out" : std::string();
      },
      "", "not empty");
  for (CLI::Option* o : app.get_options()) {
    if (o->get_items_expected_max() > 0 && o->get_expected_min() != 0) o->check(nonempty);
  }
  for (CLI::App* sub : app.get_subcommands({})) refuse_empty_values(*sub);
}

// A usage error as one message: unknown commands and misspelt options name
// the nearest right one.
std::string usage_message(CLI::App& app, const CLI::ParseError& e, int argc, char** argv) {
  CLI::App* cmd = selected(app);
  if (cmd == &app && argc > 1 && argv[1][0] != '-') {
    std::vector<std::string> names;
    for (const CLI::App* sub : app.get_subcommands({})) names.push_back(sub->get_name());
    const std::string guess = nearest(argv[1], names);
    return "unknown command '" + shown_value(argv[1]) + "'" +
           (guess.empty() ? "" : "; did you mean '" + guess + "'?") + " (lsgd --help lists them)";
  }
  std::vector<std::string> subnames;
  for (const CLI::App* sub : cmd->get_subcommands({})) subnames.push_back(sub->get_name());
  std::vector<std::string> options;
  for (const CLI::Option* o : cmd->get_options()) {
    for (const std::string& n : o->get_lnames()) options.push_back("--" + n);
  }
  for (const std::string& extra : cmd->remaining()) {
    if (extra.rfind("--", 0) == 0) {
      const std::string word = extra.substr(0, extra.find('='));
      const std::string guess = nearest(word, options);
      return "unknown option " + shown_value(word) + " for " + path_of(cmd) +
             (guess.empty() ? "" : "; did you mean " + guess + "?") + " (" + path_of(cmd) + " --help lists them)";
    }
    if (!subnames.empty()) {
      const std::string guess = nearest(extra, subnames);
      return "unknown command '" + shown_value(extra) + "' for " + path_of(cmd) +
             (guess.empty() ? "" : "; did you mean '" + guess + "'?");
    }
  }
  std::string what = e.what();
  // A flag given twice: CLI11 said "--min-gap: At Most 1 required but received 2".
  const std::size_t twice = what.find(": At Most 1 required but received ");
  if (dynamic_cast<const CLI::ArgumentMismatch*>(&e) != nullptr && twice != std::string::npos) {
    const std::string flag = what.substr(0, twice);
    std::string values;
    if (const CLI::Option* o = cmd->get_option_no_throw(flag)) {
      for (const std::string& v : o->results()) values += (values.empty() ? "'" : ", '") + shown_value(v) + "'";
    }
    return flag + " is given more than once" + (values.empty() ? "" : " (" + values + ")") +
           ": give it once (" + path_of(cmd) + " --help for the usage)";
  }
  // CLI11's "Could not convert: --threshold = VALUE" echoes the value whole.
  const std::size_t at = what.find(" = ");
  if (dynamic_cast<const CLI::ConversionError*>(&e) != nullptr && at != std::string::npos) {
    what = what.substr(0, at + 3) + shown_value(what.substr(at + 3));
  }
  return what + " (" + path_of(cmd) + " --help for the usage)";
}

// What a command printed reached standard output (a full disk, a closed
// descriptor: an error, exit 1, not a silent loss). 0 or 1, main's exit code.
int standard_output_written() {
  errno = 0;
  std::cout.flush();
  if (std::cout && std::fflush(stdout) == 0 && !std::ferror(stdout)) return 0;
  const int error = errno;
  std::cerr << "lsgd: error: cannot write standard output"
            << (error != 0 ? std::string(": ") + std::strerror(error) : std::string())
            << (error == EBADF ? " (it is closed)" : error == ENOSPC ? " (the disk is full)" : "")
            << "; what the command printed is lost" << std::endl;
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  // Descriptors 0, 1 and 2 closed by the caller would be taken by the first
  // files opened (a CSV as fd 2 would receive every diagnostic): they are
  // held by /dev/null instead.
  // Standard output is opened for reading: every write to it fails, so that
  // results meant for it are not lost silently (CommandFiles refuses a
  // command whose output would go there; main() checks what was written).
  for (int fd = 0; fd <= 2; ++fd) {
    if (::fcntl(fd, F_GETFD) == -1 && errno == EBADF &&
        ::open("/dev/null", fd == STDOUT_FILENO ? O_RDONLY : O_RDWR) != fd) {
      break;
    }
  }
  lsgd::io::remove_temporary_files_on_signal();
  // The tool computes on the CPU: OpenCV must not load an OpenCL runtime for
  // ORB (the ICD loader it may dlopen brings dynamic TLS that crashed
  // LeakSanitizer's exit check, and nothing here runs on a GPU). A value the
  // user set is kept.
  ::setenv("OPENCV_OPENCL_RUNTIME", "disabled", 0);
  lsgd::cli::set_command_line(argc, argv);
  CLI::App app{"lsgd: training-free visual loop closure detection (LSGDDN-LCD)"};
  app.set_version_flag("--version", lsgd::cli::version_text());
  app.option_defaults()->always_capture_default();  // help shows every default
  app.require_subcommand(1);
  lsgd::cli::register_run(app);
  lsgd::cli::register_eval(app);
  lsgd::cli::register_match(app);
  lsgd::cli::register_demo(app);
  lsgd::cli::register_sweep(app);
  lsgd::cli::register_bench(app);
  lsgd::cli::register_gt(app);
  lsgd::cli::register_db(app);
  lsgd::cli::register_options(app);
  hide_sentinel_defaults(app);
  read_numbers_as_typed(app);
  refuse_empty_values(app);
  // The detector runs on the calling thread; OpenCV's own thread pool (ORB,
  // RANSAC and resizing in the geometric stage) is off too, so that every
  // time the tool reports is single-thread and runs are repeatable. `lsgd
  // sweep --jobs N` runs cells on its own threads.
  cv::setNumThreads(0);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // Usage errors exit 1 like every other error (README, "Command line").
    std::cerr << "lsgd: error: " << usage_message(app, e, argc, argv) << std::endl;
    return 1;
  } catch (const std::bad_alloc&) {
    // Where no command named the file or frame (the frame loops do): still
    // not the bare "std::bad_alloc".
    std::cerr << "lsgd: error: out of memory (an allocation failed: a memory limit, or inputs too "
                 "large for this machine)"
              << std::endl;
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "lsgd: error: " << e.what() << std::endl;
    return 1;
  }
  return standard_output_written();
}
