#include "aia/core/io.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace aia {

void MakeDirs(const std::string& path) {
  if (path.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  if (ec)
    throw std::runtime_error("cannot create directory '" + path +
                             "': " + ec.message());
}

AtomicFile::AtomicFile(const std::string& path)
    : path_(path), tmp_(path + ".tmp." + std::to_string(::getpid())) {
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
