#pragma once
// Progress of long work on stderr, "[  1.2 s] multiscale-normal: encoding the details (normal)": a new
// message at once, a message that only repeats with new numbers (iteration 12, 13, ...) at most every half
// second, and the last of such a run before the next message (the detail-scale search showed its first
// candidate only); nothing with --quiet.

#include <chrono>
#include <cstdio>
#include <functional>
#include <string>

namespace msd::cli {

class ProgressPrinter {
 public:
  explicit ProgressPrinter(bool quiet) : quiet_(quiet) {}
  void operator()(const std::string& line) {
    if (quiet_) return;
    const double now = std::chrono::duration<double>(Clock::now() - start_).count();
    const std::string kind = line.substr(0, line.find_first_of("0123456789"));
    if (kind == last_kind_ && now - last_printed_ < 0.5) {
      held_ = line, held_time_ = now;
      return;
    }
    if (kind != last_kind_) flush();
    held_.clear();
    std::fprintf(stderr, "[%6.1f s] %s\n", now, line.c_str());
    last_kind_ = kind;
    last_printed_ = now;
  }
  //! Prints the message held back, if any (when the work that sent it is over).
  void flush() {
    if (!held_.empty()) std::fprintf(stderr, "[%6.1f s] %s\n", held_time_, held_.c_str());
    held_.clear();
  }
  ~ProgressPrinter() { flush(); }
  ProgressPrinter(const ProgressPrinter&) = delete;
  ProgressPrinter& operator=(const ProgressPrinter&) = delete;

 private:
  using Clock = std::chrono::steady_clock;
  bool quiet_;
  Clock::time_point start_ = Clock::now();
  std::string last_kind_;
  double last_printed_ = -1;
  std::string held_;  // the last message of the current kind not printed yet, and its time
  double held_time_ = 0;
};

}  // namespace msd::cli
