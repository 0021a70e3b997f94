// File helpers: results are written atomically (to a temporary file in the
// same directory, then renamed), so an interrupted job never leaves a
// half-written result behind.
#ifndef AIA_CORE_IO_H_
#define AIA_CORE_IO_H_

#include <cstdio>
#include <string>

namespace aia {

// Writes `content` to `path` atomically; throws std::runtime_error on failure.
void WriteFileAtomic(const std::string& path, const std::string& content);

// Creates a directory and its parents; throws std::runtime_error on failure.
void MakeDirs(const std::string& path);

// A file written through a temporary name and renamed into place by Commit().
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
