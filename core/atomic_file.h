#pragma once
//! \file Writing files so that a failed or interrupted run never leaves a truncated output behind and
//! never clobbers what was there before.

#include <string>
#include <string_view>

namespace msd {

//! Writes content to a temporary file beside path, flushes it, then renames it over path (atomic on
//! POSIX file systems). \throw InvalidInput naming the path if the folder is not writable or the disk
//! fills up; path is then untouched.
void write_file_atomically(const std::string& path, std::string_view content);

//! Reads a whole file. \throw InvalidInput naming the path if it cannot be opened or read.
std::string read_file(const std::string& path, const char* who);

}  // namespace msd
