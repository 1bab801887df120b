// The frame of a tool's main: the command line, then the work, each with its own exit code.
#pragma once

#include <cerrno>
#include <climits>
#include <cstdlib>
#include <exception>
#include <functional>
#include <iostream>
#include <stdexcept>
#include <string>

namespace line_map_eval
{
/// Walks a command line: next() steps to each argument, value() takes the one after it as the
/// current option's value.
class CommandLine
{
 public:
  CommandLine(int argc, char** argv) : argc_(argc), argv_(argv) {}
  bool next()
  {
    if (++i_ >= argc_) return false;
    arg_ = argv_[i_];
    return true;
  }
  const std::string& arg() const { return arg_; }
  /// Throws std::invalid_argument when the option is the last argument.
  std::string value()
  {
    if (i_ + 1 >= argc_) throw std::invalid_argument(arg_ + " needs a value");
    return argv_[++i_];
  }

 private:
  int argc_;
  char** argv_;
  int i_ = 0;
  std::string arg_;
};

/// The value of `option` as a whole number in [min, max]; throws std::invalid_argument naming the option and
/// the text otherwise (a sign, a fraction, trailing characters, out of range).
inline unsigned long long parseCount(const std::string& option, const std::string& text,
                                     unsigned long long min = 0, unsigned long long max = ULLONG_MAX)
{
  char* end = nullptr;
  errno = 0;
  const unsigned long long v = std::strtoull(text.c_str(), &end, 10);
  if (errno != 0 || text.empty() || *end != '\0' || text[0] == '-' || text[0] == '+' || text[0] == ' ' ||
      v < min || v > max)
    throw std::invalid_argument(option + " expects a whole number " +
                                (max == ULLONG_MAX
                                     ? ">= " + std::to_string(min)
                                     : "in [" + std::to_string(min) + ", " + std::to_string(max) + "]") +
                                ", got '" + text + "'");
  return v;
}

/// Runs `parse`: false (--help) prints the usage on stdout and returns 0; an exception prints
/// "NAME: what" + `gap` and the usage on stderr and returns 2. Then returns `run`'s exit code, or 1
/// after printing "NAME: what" on stderr when it throws.
inline int toolMain(const std::string& name, const std::function<bool()>& parse,
                    const std::function<void(std::ostream&)>& usage, const std::function<int()>& run,
                    const char* gap = "\n")
{
  try
  {
    if (!parse())
    {
      usage(std::cout);
      return 0;
    }
  }
  catch (const std::exception& e)
  {
    std::cerr << name << ": " << e.what() << gap;
    usage(std::cerr);
    return 2;
  }
  try
  {
    return run();
  }
  catch (const std::exception& e)
  {
    std::cerr << name << ": " << e.what() << "\n";
    return 1;
  }
}
}  // namespace line_map_eval
