#include "msdeform/core/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include "msdeform/core/errors.h"

namespace msd {

void write_file_atomically(const std::string& path, std::string_view content) {
  std::string tmpl = path + ".tmp-XXXXXX";
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

std::string read_file(const std::string& path, const char* who) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InvalidInput(std::string(who) + ": cannot open " + path + ": " + std::strerror(errno));
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InvalidInput(std::string(who) + ": error while reading " + path);
  return std::move(ss).str();
}

}  // namespace msd
