#include "msdeform/core/atomic_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include "msdeform/core/errors.h"

namespace msd {

bool same_file(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (fs::exists(a, error) && fs::exists(b, error)) return fs::equivalent(a, b, error);
  return fs::weakly_canonical(a, error) == fs::weakly_canonical(b, error);
}

void check_writable(const std::string& path, const char* who) {
  const auto fail = [&](const std::string& what) {
    throw InvalidInput(std::string(who) + " " + path + ": " + what + "; nothing was computed");
  };
  if (path.empty()) fail("empty output path");
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) fail("is a folder");
    // The mode bits too: root may write anything, but a file nobody may write is meant to stay.
    if (::access(path.c_str(), W_OK) != 0 || (st.st_mode & 0222) == 0) fail("is read-only (it is not replaced)");
  } else if (errno != ENOENT) {
    fail(std::strerror(errno));
  }
  const size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) fail("its folder " + dir + " does not exist");
  if (::access(dir.c_str(), W_OK) != 0) fail("its folder " + dir + " is not writable");
  const std::string name = path.substr(slash == std::string::npos ? 0 : slash + 1);
  if (name.size() > 255) fail("the file name is longer than 255 bytes");
}

void write_file_atomically(const std::string& path, std::string_view content) {
  // The temporary file is a short hidden name in the same folder (rename needs one file system), so a
  // legal name of up to 255 bytes stays legal.
  const size_t slash = path.find_last_of('/');
  std::string tmpl = (slash == std::string::npos ? std::string() : path.substr(0, slash + 1)) + ".msd-XXXXXX";
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  const int fd = mkstemp(name.data());
  if (fd < 0)
    throw InvalidInput("cannot write " + path + ": " + std::strerror(errno) +
                       " (does the folder exist and is it writable?)");
  const mode_t mask = umask(0);
  umask(mask);
  fchmod(fd, 0666 & ~mask);  // mkstemp creates 0600; give the result ordinary permissions
  const char* data = content.data();
  size_t left = content.size();
  bool ok = true;
  while (left > 0) {
    const ssize_t n = ::write(fd, data, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      ok = false;
      break;
    }
    data += n;
    left -= static_cast<size_t>(n);
  }
  const int saved = errno;
  if (::close(fd) != 0) ok = false;
  if (!ok || std::rename(name.data(), path.c_str()) != 0) {
    const int err = ok ? errno : saved;
    std::remove(name.data());
    throw InvalidInput("cannot write " + path + ": " + std::strerror(err) + " (the previous file, if any, is untouched)");
  }
}

FileText::FileText(const std::string& path, const char* who) {
  const auto fail = [&](const std::string& what) { throw InvalidInput(std::string(who) + ": " + path + ": " + what); };
  // Closed on every way out (a mapping outlives its descriptor).
  struct Descriptor {
    int fd;
    ~Descriptor() {
      if (fd >= 0) ::close(fd);
    }
  } const file{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  const int fd = file.fd;
  if (fd < 0) fail(std::string("cannot open it: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0) fail(std::string("cannot read it: ") + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) fail("is a folder, not a file");
  if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) fail("is a device, not a file");  // /dev/zero: endless
  if (S_ISREG(st.st_mode) && st.st_size > 0) {
    map_size_ = static_cast<size_t>(st.st_size);
    map_ = ::mmap(nullptr, map_size_, PROT_READ, MAP_PRIVATE, fd, 0);
    if (map_ == MAP_FAILED) {
      map_ = nullptr;
      fail(std::string("cannot map it: ") + std::strerror(errno));
    }
    ::madvise(map_, map_size_, MADV_SEQUENTIAL);
    text_ = std::string_view(static_cast<const char*>(map_), map_size_);
  } else {  // empty, or a pipe (e.g. <(command)): read what comes, up to a bound
    constexpr size_t kMaxPipeBytes = size_t(1) << 30;
    char buffer[1 << 16];
    while (true) {
      if (copy_.size() > kMaxPipeBytes) fail("more than 1 GiB from a pipe; give a file");
      const ssize_t n = ::read(fd, buffer, sizeof buffer);
      if (n == 0) break;
      if (n < 0) {
        if (errno == EINTR) continue;
        fail(std::string("error while reading it: ") + std::strerror(errno));
      }
      copy_.append(buffer, static_cast<size_t>(n));
    }
    text_ = copy_;
  }
  if (text_.substr(0, 3) == "\xEF\xBB\xBF") text_.remove_prefix(3);  // a UTF-8 byte-order mark
}

FileText::~FileText() {
  if (map_) ::munmap(map_, map_size_);
}

std::string printable(std::string_view text) {
  std::string out;
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 32 && u < 127) {
      out += c;
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02X", u);
      out += hex;
    }
  }
  return out;
}

std::string read_file(const std::string& path, const char* who) { return std::string(FileText(path, who).text()); }

}  // namespace msd
