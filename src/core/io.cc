#include "aia/core/io.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "aia/core/error.h"

namespace aia {

namespace {

// What a stat says a path is, when not a regular file.
std::string KindOf(mode_t mode) {
  if (S_ISREG(mode)) return "";
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a named pipe (FIFO)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a file";
}

}  // namespace

std::string NonRegularKind(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) return "";
  return KindOf(st.st_mode);
}

std::string TemporaryNameProblem(const std::string& path) {
  const std::filesystem::path p(path);
  const std::string dir =
      p.has_parent_path() ? p.parent_path().string() : std::string(".");
  long max = ::pathconf(dir.c_str(), _PC_NAME_MAX);
  if (max <= 0) max = NAME_MAX;
  // The longer of TemporaryPath's two forms: ".STEM.tmp.PID.EXT".
  const std::size_t longest =
      std::filesystem::path(TemporaryPath(path, /*keep_extension=*/true))
          .filename()
          .string()
          .size();
  if (static_cast<long>(longest) <= max) return "";
  const long room =
      max - static_cast<long>(longest - p.filename().string().size());
  return "cannot write '" + path + "': its name has " +
         std::to_string(p.filename().string().size()) +
         " characters, and it is written under a temporary name " +
         std::to_string(longest - p.filename().string().size()) +
         " longer first (the file system takes " + std::to_string(max) +
         "): give a name of at most " + std::to_string(room) + " characters";
}

std::string OutputFileProblem(const std::string& path,
                              const std::string& written) {
  if (std::string longer = TemporaryNameProblem(path); !longer.empty())
    return longer;
  const std::string kind = NonRegularKind(path);
  if (kind.empty()) return "";
  return "cannot write '" + path + "'" +
         (written.empty() ? "" : " (" + written + ")") + ": it is " + kind +
         ", not a regular file; remove it or give another path";
}

int OpenRegularFile(const std::string& path, std::string* why) {
  // O_NONBLOCK: opening a FIFO without a writer returns at once instead of
  // waiting for one (which no signal ended); it is cleared for the reads.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    *why = std::strerror(errno);
    return -1;
  }
  struct stat st;
  if (::fstat(fd, &st) != 0) {
    *why = std::strerror(errno);
    ::close(fd);
    return -1;
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    throw std::runtime_error("cannot read file: it is " + KindOf(st.st_mode) +
                             ", not a regular file");
  }
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  return fd;
}

std::string ReadFile(const std::string& path, std::uintmax_t max_bytes) {
  std::string why;
  const int fd = OpenRegularFile(path, &why);
  if (fd < 0) throw std::runtime_error("cannot read file: " + why);
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st;
  if (::fstat(fd, &st) == 0 &&
      static_cast<std::uintmax_t>(st.st_size) > max_bytes)
    throw std::runtime_error("file of " + std::to_string(st.st_size) +
                             " bytes; at most " + std::to_string(max_bytes) +
                             " bytes are read");
  std::string text;
  char buffer[1 << 16];
  while (true) {
    const ssize_t n = ::read(fd, buffer, sizeof(buffer));
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(std::string("cannot read file: ") +
                               std::strerror(errno));
    }
    if (n == 0) break;
    text.append(buffer, static_cast<std::size_t>(n));
    if (text.size() > max_bytes)  // it grew while being read
      throw std::runtime_error("file larger than " + std::to_string(max_bytes) +
                               " bytes");
  }
  return text;
}

LineReader::LineReader(const std::string& path, std::size_t max_line)
    : path_(path), max_line_(max_line) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0 && errno == ENOENT) return;  // none
  std::string why;
  fd_ = OpenRegularFile(path, &why);
  if (fd_ < 0) throw std::runtime_error("cannot read file: " + why);
}

LineReader::~LineReader() {
  if (fd_ >= 0) ::close(fd_);
}

bool LineReader::Fill() {
  if (eof_ || fd_ < 0) return false;
  if (at_ > 0) {
    buffer_.erase(0, at_);
    at_ = 0;
  }
  char chunk[1 << 16];
  while (true) {
    const ssize_t n = ::read(fd_, chunk, sizeof(chunk));
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error("cannot read file: " +
                               std::string(std::strerror(errno)));
    }
    if (n == 0) {
      eof_ = true;
      return false;
    }
    buffer_.append(chunk, static_cast<std::size_t>(n));
    return true;
  }
}

bool LineReader::Next(std::string* line) {
  if (fd_ < 0) return false;
  std::size_t searched = at_;
  while (true) {
    const std::size_t nl = buffer_.find('\n', searched);
    if (nl != std::string::npos && nl - at_ <= max_line_) {
      line->assign(buffer_, at_, nl - at_);
      at_ = nl + 1;
      ++line_number_;
      return true;
    }
    if (buffer_.size() - at_ > max_line_) {
      throw LineTooLong("line " + std::to_string(line_number_ + 1) +
                        " is longer than " + std::to_string(max_line_) +
                        " bytes");
    }
    const std::size_t had = buffer_.size() - at_;
    if (!Fill()) {
      if (buffer_.size() == at_) return false;
      line->assign(buffer_, at_, std::string::npos);  // a last line
      at_ = buffer_.size();
      ++line_number_;
      return true;
    }
    searched = at_ + had;  // Fill() moved the unread bytes to the front
  }
}

bool LockedByAnotherProcess(const std::string& path) {
  // The kernel's table of locks (/proc/locks) names each flock's file by
  // device and inode and its holder by pid: no lock is taken to ask, and a
  // lock of this process, whichever copy of this library took it (the torch
  // plugin has its own), does not count.
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) return false;
  std::ifstream locks("/proc/locks");
  const unsigned long long inode = st.st_ino;
  const long self = static_cast<long>(::getpid());
  std::string line;
  while (std::getline(locks, line)) {
    // "1: FLOCK  ADVISORY  WRITE 1234 08:01:56789 0 EOF"
    std::istringstream in(line);
    std::string index, kind, mode, access, file;
    long pid = 0;
    if (!(in >> index >> kind) || kind != "FLOCK") continue;
    if (!(in >> mode >> access >> pid >> file)) continue;
    unsigned ma = 0, mi = 0;
    unsigned long long ino = 0;
    if (std::sscanf(file.c_str(), "%x:%x:%llu", &ma, &mi, &ino) != 3) continue;
    // The inode decides: under overlayfs (containers) the table names the
    // upper layer's device, which stat() does not give.
    if (ino == inode && pid != self) return true;
  }
  return false;
}

FileLock::FileLock(const std::string& path) {
  // A folder is locked through its own descriptor: no file is added to it.
  struct stat st;
  const bool dir = ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
  // O_NONBLOCK: nothing here may wait for a FIFO's other end.
  fd_ = dir ? ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC)
            : ::open(path.c_str(), O_RDWR | O_CREAT | O_NONBLOCK | O_CLOEXEC,
                     0644);
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

std::string UnwritableDirProblem(const std::string& dir) {
  const std::string probe =
      dir + "/.aia-probe.tmp." + std::to_string(::getpid());
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0644);
  if (fd < 0) return "cannot write into '" + dir + "': " + std::strerror(errno);
  ::close(fd);
  ::unlink(probe.c_str());
  return "";
}

void CheckReplaceableFile(const std::string& path) {
  // `dir/`, `dir/.` or `..` name a folder, whether it exists yet or not.
  const std::string name = std::filesystem::path(path).filename().string();
  if (!path.empty() && (name.empty() || name == "." || name == ".."))
    ThrowCannotWrite(path, "it names a folder, not a file; give a file's path");
  const std::string kind = NonRegularKind(path);
  if (!kind.empty())
    ThrowCannotWrite(
        path, "it is " + kind + ", not a regular file; give a file's path");
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
      throw InputError::Flag(
          flag, "'" + output + "'" +
                    (written.empty() ? "" : " (" + written + ")") + " is " +
                    in.what + "; choose another path");
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
  // Never blocks: a FIFO at the temporary name (not made by aia) is refused
  // by the open itself (no reader: ENXIO) or by the check after it.
  const int fd =
      ::open(tmp_.c_str(),
             O_WRONLY | O_CREAT | O_TRUNC | O_NONBLOCK | O_CLOEXEC, 0644);
  if (fd < 0) ThrowCannotWriteErrno(path, errno);
  struct stat st;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    ThrowCannotWrite(path,
                     "its temporary '" + tmp_ + "' is not a regular file");
  }
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  file_ = ::fdopen(fd, "wb");
  if (file_ == nullptr) {
    const int err = errno;
    ::close(fd);
    std::remove(tmp_.c_str());
    ThrowCannotWriteErrno(path, err);
  }
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
    ThrowCannotWriteErrno(path_, err);
  }
}

void WriteFileAtomic(const std::string& path, const std::string& content) {
  AtomicFile f(path);
  errno = 0;
  if (std::fwrite(content.data(), 1, content.size(), f.get()) != content.size())
    ThrowCannotWriteErrno(path, errno);
  f.Commit();
}

void ThrowCannotWrite(const std::string& path, const std::string& why) {
  throw std::runtime_error("cannot write '" + path + "': " + why);
}

void ThrowCannotWriteErrno(const std::string& path, int err) {
  ThrowCannotWrite(path, std::strerror(err != 0 ? err : ENOSPC));
}

}  // namespace aia
