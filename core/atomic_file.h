#pragma once
//! \file Writing files so that a failed or interrupted run never leaves a truncated output behind and
//! never clobbers what was there before; reading them so that a bad file costs what was read of it.

#include <string>
#include <string_view>

namespace msd {

//! Writes content to a temporary file beside path, flushes it, then renames it over path (atomic on
//! POSIX file systems). \throw InvalidInput naming the path if the folder is not writable or the disk
//! fills up; path is then untouched.
void write_file_atomically(const std::string& path, std::string_view content);

//! Checks, before any work, that path can be written: its folder exists and is writable, and path is
//! not a folder or a read-only file (which write_file_atomically would replace). \throw InvalidInput
//! naming who (e.g. "-o") and the path.
void check_writable(const std::string& path, const char* who);

//! Whether two paths name one file: the same existing file (links followed), or, when either does not
//! exist yet, the same spelling once made absolute. Used so that no output replaces an input.
bool same_file(const std::string& a, const std::string& b);

//! A file's bytes, mapped read-only: pages are read from disk as a reader touches them, so a reader that
//! stops at a bad first line of a 1 GB file costs that line, not the file. Pipes (e.g. `<(command)`) are
//! read whole, up to 1 GiB. \throw InvalidInput naming the path if it does not exist, is a folder or a
//! device, cannot be opened or read, or a pipe gives more than 1 GiB.
class FileText {
 public:
  FileText(const std::string& path, const char* who);
  ~FileText();
  FileText(const FileText&) = delete;
  FileText& operator=(const FileText&) = delete;
  //! The bytes, without a leading UTF-8 byte-order mark.
  std::string_view text() const { return text_; }

 private:
  void* map_ = nullptr;
  size_t map_size_ = 0;
  std::string copy_;  // non-regular files
  std::string_view text_;
};

//! Longest token a text reader scans as one number: a longer run (binary data) is refused there rather
//! than scanned to its end.
constexpr size_t kMaxNumberLength = 400;

//! text as it can be shown in a message: bytes outside printable ASCII as \xHH (a byte-order mark or
//! binary data would otherwise be invisible or garble the terminal).
std::string printable(std::string_view text);

//! Reads a whole file into memory (FileText(path, who).text(), copied).
std::string read_file(const std::string& path, const char* who);

}  // namespace msd
