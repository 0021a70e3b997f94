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

#include "aia/core/error.h"

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
    std::string pid = name.substr(at + 5);
    // NAME.tmp.PID.EXT (TemporaryPath with keep_extension): a short
    // alphanumeric extension after the PID.
    if (const std::size_t dot = pid.find('.'); dot != std::string::npos) {
      const std::string ext = pid.substr(dot + 1);
      if (ext.empty() || ext.size() > 8 ||
          ext.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789") !=
              std::string::npos)
        continue;
      pid.resize(dot);
    }
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

bool SameFile(const std::string& a, const std::string& b) {
  std::error_code ec;
  return !a.empty() && !b.empty() && std::filesystem::equivalent(a, b, ec) &&
         !ec;
}

void CheckNotAnInput(const std::string& output, const std::string& flag,
                     const std::vector<InputFile>& inputs,
                     const std::string& written) {
  for (const InputFile& in : inputs)
    if (SameFile(output, in.path))
      throw InputError("command line", 0, flag,
                       "'" + output + "'" +
                           (written.empty() ? "" : " (" + written + ")") +
                           " is " + in.what + "; choose another path");
}

std::string TemporaryPath(const std::string& path, bool keep_extension) {
  const std::string pid = std::to_string(::getpid());
  if (!keep_extension) return path + ".tmp." + pid;
  const std::filesystem::path p(path);
  return (p.parent_path() /
          ("." + p.stem().string() + ".tmp." + pid + p.extension().string()))
      .string();
}

AtomicFile::AtomicFile(const std::string& path)
    : path_(path), tmp_(TemporaryPath(path)) {
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
  // errno is taken where the first step fails (a full disk shows at the
  // flush, the sync or the close of buffered data).
  // A write that failed earlier (unchecked fwrite calls of the streaming
  // writers) leaves the stream's error flag.
  int err = 0;
  errno = 0;
  if (std::fflush(file_) != 0 || ::fsync(fileno(file_)) != 0) {
    err = errno;
  } else if (std::ferror(file_)) {
    err = errno != 0 ? errno : EIO;
  }
  if (std::fclose(file_) != 0 && err == 0) err = errno;
  file_ = nullptr;
  if (err == 0 && std::rename(tmp_.c_str(), path_.c_str()) != 0) err = errno;
  if (err != 0) {
    std::remove(tmp_.c_str());
    throw std::runtime_error("cannot write '" + path_ +
                             "': " + std::strerror(err));
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
