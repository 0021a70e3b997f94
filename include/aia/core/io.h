// File helpers: results are written atomically (to a temporary file in the
// same directory, then renamed), so an interrupted job never leaves a
// half-written result behind.
#ifndef AIA_CORE_IO_H_
#define AIA_CORE_IO_H_

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace aia {

// Writes `content` to `path` atomically; throws std::runtime_error on failure.
void WriteFileAtomic(const std::string& path, const std::string& content);

// The whole content of a regular file of at most `max_bytes` bytes. Throws
// std::runtime_error with a one-line reason otherwise ("not a regular file"
// for a FIFO, a device or a directory: nothing blocks or reads forever).
std::string ReadFile(const std::string& path, std::uintmax_t max_bytes);

// What `path` is when it exists (after links) and is not a regular file: "a
// folder", "a named pipe (FIFO)", "a character device", "a block device", "a
// socket"; "" for a regular file or a path that does not exist. A stat, so
// nothing can block.
std::string NonRegularKind(const std::string& path);

// Why `path`'s name is too long to be written, or "": a file is written
// under TemporaryPath first, up to 17 characters longer, and a name the file
// system takes could fail only there, after the work.
std::string TemporaryNameProblem(const std::string& path);

// Why `path` cannot be an output file, or "" when it can (it does not exist
// or is a regular file, and TemporaryNameProblem has nothing): "cannot
// write 'PATH' (WRITTEN): it is a named pipe (FIFO), not a regular file;
// remove it or give another path". Commands check every file they write
// with it before any work.
std::string OutputFileProblem(const std::string& path,
                              const std::string& written = "");

// Opens an existing regular file for reading without ever blocking: the open
// itself cannot wait (O_NONBLOCK, then cleared), and a FIFO, device or folder
// is refused ("it is a named pipe (FIFO), not a regular file"). Returns the
// descriptor, or -1 with *why set (errno's text) when it cannot be opened;
// throws std::runtime_error when it is not a regular file.
int OpenRegularFile(const std::string& path, std::string* why);

// What LineReader::Next throws for a line longer than its cap.
class LineTooLong : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A text file read line by line, each line at most `max_line` bytes (a line
// of 3 GB of NULs is an error, not 12 GB of memory). Opened with
// OpenRegularFile.
class LineReader {
 public:
  // Throws std::runtime_error when the path is not a regular file or cannot
  // be opened; `exists()` is false when it does not exist.
  LineReader(const std::string& path, std::size_t max_line);
  ~LineReader();
  LineReader(const LineReader&) = delete;
  LineReader& operator=(const LineReader&) = delete;

  bool exists() const { return fd_ >= 0; }
  // The next line without its '\n' (a last line may lack one). False at the
  // end; throws LineTooLong ("line N is longer than M bytes") or
  // std::runtime_error when a read fails.
  bool Next(std::string* line);
  long line_number() const { return line_number_; }

 private:
  bool Fill();
  std::string path_;
  std::size_t max_line_;
  int fd_ = -1;
  std::string buffer_;
  std::size_t at_ = 0;
  bool eof_ = false;
  long line_number_ = 0;
};

// Creates a directory and its parents; throws std::runtime_error on failure.
void MakeDirs(const std::string& path);

// Whether a file can be made in folder `dir` (one is created and removed
// again: permissions, read-only file systems and folders like /proc all
// answer this the same way): "" if so, else "cannot write into 'DIR':
// <errno text>".
std::string UnwritableDirProblem(const std::string& dir);

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

// Whether another process holds a FileLock on `path` now (a reader's check
// that no job is writing it; it takes no lock itself). A FileLock of this
// process does not count, nor a path that does not exist (the reader then
// says what is wrong with it). Read from /proc/locks by inode (Linux).
bool LockedByAnotherProcess(const std::string& path);

// Where this process writes `path` before renaming it into place:
// `PATH.tmp.PID`, or, with `keep_extension`, `DIR/.STEM.tmp.PID.EXT` for
// writers that choose the format by the extension (a video's container).
std::string TemporaryPath(const std::string& path, bool keep_extension = false);

// Removes the leftovers of writers that were killed: files `NAME.tmp.PID`
// and `NAME.tmp.PID.EXT` (TemporaryPath) in `dir`, NAME starting with
// `prefix`, whose process PID is gone. Returns how many were removed.
int RemoveStaleTemporaries(const std::string& dir,
                           const std::string& prefix = "");

// aia's I/O error for an output: std::runtime_error("cannot write 'PATH':
// WHY"); the second with the text of errno `err`, where 0 (a short write
// that set none) reads as a full disk (ENOSPC).
[[noreturn]] void ThrowCannotWrite(const std::string& path,
                                   const std::string& why);
[[noreturn]] void ThrowCannotWriteErrno(const std::string& path, int err);

// Throws std::runtime_error("cannot write 'PATH': it is a named pipe (FIFO),
// not a regular file; ...") when `path` exists and is not a regular file
// (after links): renaming a finished file onto it would replace a folder, a
// device such as /dev/null, or a pipe; likewise ("...: it names a folder")
// when its last component is empty, `.` or `..` (`dir/`), made yet or not.
void CheckReplaceableFile(const std::string& path);

// Whether `a` and `b` name one existing file (std::filesystem::equivalent:
// through symbolic and hard links, `./` and `..`).
bool SameFile(const std::string& a, const std::string& b);

// A file a command reads, for the check that no output replaces it.
struct InputFile {
  std::string path;
  std::string what;  // "the input scenario", "the model (--init)", ...
};

// Throws InputError::Flag(flag, "'OUT' is WHAT; choose another path") when
// `output` is one of `inputs` (SameFile): writing it would replace an input.
// `written`, when not empty, says how the output comes from the flag
// ("written next to the video"). Outputs that do not exist yet are no input.
void CheckNotAnInput(const std::string& output, const std::string& flag,
                     const std::vector<InputFile>& inputs,
                     const std::string& written = "");

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
