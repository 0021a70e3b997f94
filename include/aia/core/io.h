// File helpers: results are written atomically (to a temporary file in the
// same directory, then renamed), so an interrupted job never leaves a
// half-written result behind.
#ifndef AIA_CORE_IO_H_
#define AIA_CORE_IO_H_

#include <cstdint>
#include <cstdio>
#include <string>

namespace aia {

// Writes `content` to `path` atomically; throws std::runtime_error on failure.
void WriteFileAtomic(const std::string& path, const std::string& content);

// The whole content of a regular file of at most `max_bytes` bytes. Throws
// std::runtime_error with a one-line reason otherwise ("not a regular file"
// for a FIFO, a device or a directory: nothing blocks or reads forever).
std::string ReadFile(const std::string& path, std::uintmax_t max_bytes);

// Creates a directory and its parents; throws std::runtime_error on failure.
void MakeDirs(const std::string& path);

// An exclusive advisory lock (flock) on `path`: a folder, or a file
// (created if needed, never written), held until destroyed or until the
// process ends: a killed job leaves no stale lock. Throws
// std::runtime_error when another process (or another FileLock of this one)
// holds it.
class FileLock {
 public:
  explicit FileLock(const std::string& path);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_ = -1;
};

// Removes the leftovers of AtomicFile writers that were killed: files
// `NAME.tmp.PID` in `dir`, NAME starting with `prefix`, whose process PID
// is gone. Returns how many were removed.
int RemoveStaleTemporaries(const std::string& dir,
                           const std::string& prefix = "");

// Throws std::runtime_error("cannot write 'PATH': ...") when `path` exists
// and is not a regular file (after links): renaming a finished file onto it
// would replace a folder, a device such as /dev/null, or a pipe.
void CheckReplaceableFile(const std::string& path);

// A file written through a temporary name and renamed into place by Commit().
// The path must be new or a regular file (CheckReplaceableFile).
// Destroyed without Commit(), it removes the temporary file.
class AtomicFile {
 public:
  explicit AtomicFile(const std::string& path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::FILE* get() { return file_; }
  void Commit();

 private:
  std::string path_, tmp_;
  std::FILE* file_ = nullptr;
};

}  // namespace aia

#endif  // AIA_CORE_IO_H_
