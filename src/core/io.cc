#include "aia/core/io.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <memory>
#include <stdexcept>

namespace aia {

std::string ReadFile(const std::string& path, std::uintmax_t max_bytes) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0)
    throw std::runtime_error(std::string("cannot read file: ") +
                             std::strerror(errno));
  if (!S_ISREG(st.st_mode))
    throw std::runtime_error(
        "cannot read file: not a regular file (a directory, device or pipe)");
  if (static_cast<std::uintmax_t>(st.st_size) > max_bytes)
    throw std::runtime_error("file of " + std::to_string(st.st_size) +
                             " bytes; at most " + std::to_string(max_bytes) +
                             " bytes are read");
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(
      std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f)
    throw std::runtime_error(std::string("cannot read file: ") +
                             std::strerror(errno));
  std::string text;
  char buffer[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof(buffer), f.get())) > 0) {
    text.append(buffer, n);
    if (text.size() > max_bytes)  // it grew while being read
      throw std::runtime_error("file larger than " + std::to_string(max_bytes) +
                               " bytes");
  }
  if (std::ferror(f.get()))
    throw std::runtime_error(std::string("cannot read file: ") +
                             std::strerror(errno));
  return text;
}

FileLock::FileLock(const std::string& path) {
  // A folder is locked through its own descriptor: no file is added to it.
  struct stat st;
  const bool dir = ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
  fd_ = dir ? ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC)
            : ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw std::runtime_error("cannot open '" + path +
                             "' to lock it: " + std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    if (err != EWOULDBLOCK)
      throw std::runtime_error("cannot lock '" + path +
                               "': " + std::strerror(err));
    throw std::runtime_error(
        "'" + path +
        "' is in use by another aia job (it holds the lock); wait for it to "
        "end or use another folder");
  }
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

int RemoveStaleTemporaries(const std::string& dir, const std::string& prefix) {
  namespace fs = std::filesystem;
  std::error_code ec;
  int removed = 0;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const std::size_t at = name.rfind(".tmp.");
    if (at == std::string::npos || name.compare(0, prefix.size(), prefix) != 0)
      continue;
    const std::string pid = name.substr(at + 5);
    if (pid.empty() || pid.size() > 9 ||
        pid.find_first_not_of("0123456789") != std::string::npos)
      continue;
    const pid_t p = static_cast<pid_t>(std::stol(pid));
    if (p == ::getpid() || ::kill(p, 0) == 0 || errno != ESRCH) continue;
    std::error_code rm;
    if (fs::remove(it->path(), rm)) ++removed;
  }
  return removed;
}

void MakeDirs(const std::string& path) {
  if (path.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  if (ec)
    throw std::runtime_error("cannot create directory '" + path +
                             "': " + ec.message());
}

void CheckReplaceableFile(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
    throw std::runtime_error("cannot write '" + path +
                             "': it exists and is not a regular file (a "
                             "folder, device or pipe); give a file's path");
}

AtomicFile::AtomicFile(const std::string& path)
    : path_(path), tmp_(path + ".tmp." + std::to_string(::getpid())) {
  CheckReplaceableFile(path);
  file_ = std::fopen(tmp_.c_str(), "wb");
  if (file_ == nullptr)
    throw std::runtime_error("cannot write '" + path +
                             "': " + std::strerror(errno));
}

AtomicFile::~AtomicFile() {
  if (file_ != nullptr) {
    std::fclose(file_);
    std::remove(tmp_.c_str());
  }
}

void AtomicFile::Commit() {
  const bool ok = std::fflush(file_) == 0 && ::fsync(fileno(file_)) == 0;
  std::fclose(file_);
  file_ = nullptr;
  if (!ok || std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    std::remove(tmp_.c_str());
    throw std::runtime_error("cannot write '" + path_ +
                             "': " + std::strerror(errno));
  }
}

void WriteFileAtomic(const std::string& path, const std::string& content) {
  AtomicFile f(path);
  if (std::fwrite(content.data(), 1, content.size(), f.get()) != content.size())
    throw std::runtime_error("cannot write '" + path +
                             "': " + std::strerror(errno));
  f.Commit();
}

}  // namespace aia
