// libFuzzer: bytes as a model file (TorchScript zip) -> IgbNet::Load. A file
// that is not a model, or whose tensors do not match its metadata, is an
// InputError; nothing else escapes.
//
// Byte mutations of a zip mostly break its CRC-32s, so that the checks
// behind them (a tensor's size against its entry's, issue 37) were never
// reached. The custom mutator below mutates, two times in three, the
// unpacked content of one entry (a tensor's bytes cut, emptied or grown;
// data.pkl's shapes and strides) and writes the archive again with valid
// sizes and CRC-32s; the third time it mutates the bytes as they are. The
// TorchScript code entries are left alone: a model file is code, and code
// crafted with valid checksums is trusted as any program is
// (docs/hardening.md); the data is not.
#include <zlib.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "aia/core/error.h"
#include "aia/learning/network.h"
#include "fuzz_support.h"

extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size,
                                        std::size_t max_size);

namespace {

struct Entry {
  std::string name;
  std::string content;  // unpacked
};

std::uint32_t U16(const std::uint8_t* p) { return p[0] | p[1] << 8; }
std::uint32_t U32(const std::uint8_t* p) { return U16(p) | U16(p + 2) << 16; }

// The entries of a zip (stored or deflated), or false when it is not one.
bool ReadZip(const std::uint8_t* b, std::size_t n, std::vector<Entry>* out) {
  if (n < 22) return false;
  std::size_t eocd = n - 22;
  while (U32(b + eocd) != 0x06054b50) {
    if (eocd == 0 || n - eocd > 65557) return false;
    --eocd;
  }
  const std::uint32_t count = U16(b + eocd + 10);
  std::size_t at = U32(b + eocd + 16);
  for (std::uint32_t e = 0; e < count; ++e) {
    if (at + 46 > n || U32(b + at) != 0x02014b50) return false;
    const std::uint32_t method = U16(b + at + 10), crc = U32(b + at + 16),
                        size = U32(b + at + 20), unpacked = U32(b + at + 24),
                        name = U16(b + at + 28),
                        skip = name + U16(b + at + 30) + U16(b + at + 32);
    const std::size_t local = U32(b + at + 42);
    if (at + 46 + skip > n || local + 30 > n) return false;
    const std::size_t data =
        local + 30 + U16(b + local + 26) + U16(b + local + 28);
    if (data + size > n || unpacked > (1u << 24)) return false;
    Entry entry;
    entry.name.assign(reinterpret_cast<const char*>(b + at + 46), name);
    if (method == 0) {
      entry.content.assign(reinterpret_cast<const char*>(b + data), size);
    } else if (method == 8) {
      entry.content.assign(unpacked, '\0');
      z_stream z{};
      if (inflateInit2(&z, -MAX_WBITS) != Z_OK) return false;
      z.next_in = const_cast<Bytef*>(b + data);
      z.avail_in = size;
      z.next_out = reinterpret_cast<Bytef*>(entry.content.data());
      z.avail_out = unpacked;
      const int rc = inflate(&z, Z_FINISH);
      inflateEnd(&z);
      if (rc != Z_STREAM_END) return false;
    } else {
      return false;
    }
    // An entry damaged by a byte mutation is not rewritten with a fresh
    // CRC-32: that would pass a damaged code entry off as intact.
    if (crc32(0L, reinterpret_cast<const Bytef*>(entry.content.data()),
              static_cast<uInt>(entry.content.size())) != crc)
      return false;
    out->push_back(std::move(entry));
    at += 46 + skip;
  }
  return !out->empty();
}

void Put16(std::string* s, std::uint32_t v) {
  s->push_back(static_cast<char>(v & 0xff));
  s->push_back(static_cast<char>(v >> 8 & 0xff));
}
void Put32(std::string* s, std::uint32_t v) {
  Put16(s, v & 0xffff);
  Put16(s, v >> 16);
}

// A zip of stored entries with their sizes and CRC-32s right.
std::string WriteZip(const std::vector<Entry>& entries) {
  std::string out, directory;
  for (const Entry& e : entries) {
    const std::uint32_t crc = static_cast<std::uint32_t>(
        crc32(0L, reinterpret_cast<const Bytef*>(e.content.data()),
              static_cast<uInt>(e.content.size())));
    const std::uint32_t size = static_cast<std::uint32_t>(e.content.size());
    const std::uint32_t offset = static_cast<std::uint32_t>(out.size());
    Put32(&out, 0x04034b50);
    for (std::uint32_t v : {20u, 0u, 0u, 0u, 0x21u}) Put16(&out, v);
    Put32(&out, crc);
    Put32(&out, size);
    Put32(&out, size);
    Put16(&out, static_cast<std::uint32_t>(e.name.size()));
    Put16(&out, 0);
    out += e.name;
    out += e.content;
    Put32(&directory, 0x02014b50);
    for (std::uint32_t v : {20u, 20u, 0u, 0u, 0u, 0x21u}) Put16(&directory, v);
    Put32(&directory, crc);
    Put32(&directory, size);
    Put32(&directory, size);
    Put16(&directory, static_cast<std::uint32_t>(e.name.size()));
    for (int i = 0; i < 4; ++i) Put16(&directory, 0);  // extra .. internal
    Put32(&directory, 0);                              // external attributes
    Put32(&directory, offset);
    directory += e.name;
  }
  const std::uint32_t at = static_cast<std::uint32_t>(out.size());
  out += directory;
  Put32(&out, 0x06054b50);
  Put16(&out, 0);
  Put16(&out, 0);
  Put16(&out, static_cast<std::uint32_t>(entries.size()));
  Put16(&out, static_cast<std::uint32_t>(entries.size()));
  Put32(&out, static_cast<std::uint32_t>(directory.size()));
  Put32(&out, at);
  Put16(&out, 0);
  return out;
}

// One entry's content changed: a tensor's bytes cut, emptied, grown or
// mutated; data.pkl (shapes, strides, storage sizes) mutated.
void MutateEntry(Entry* e, std::mt19937* rng) {
  std::string& c = e->content;
  switch ((*rng)() % 5) {
    case 0:
      c.clear();
      break;
    case 1:
      c.resize(c.size() - std::min<std::size_t>(c.size(), 1 + (*rng)() % 8));
      break;
    case 2:
      c.resize(c.size() / 2);
      break;
    case 3:
      c.append(1 + (*rng)() % 8, '\0');
      break;
    default: {
      const std::size_t old = c.size(), max = old * 2 + 64;
      c.resize(max);
      c.resize(LLVMFuzzerMutate(reinterpret_cast<std::uint8_t*>(c.data()), old,
                                max));
    }
  }
}

}  // namespace

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data,
                                               std::size_t size,
                                               std::size_t max_size,
                                               unsigned int seed) {
  std::mt19937 rng(seed);
  std::vector<Entry> entries;
  if (rng() % 3 == 0 || !ReadZip(data, size, &entries))
    return LLVMFuzzerMutate(data, size, max_size);
  // A tensor's entry, or the pickle that declares the tensors.
  std::vector<std::size_t> targets;
  for (std::size_t i = 0; i < entries.size(); ++i)
    if (entries[i].name.find("/data/") != std::string::npos ||
        entries[i].name.find("/constants/") != std::string::npos ||
        entries[i].name.find("data.pkl") != std::string::npos ||
        entries[i].name.find("constants.pkl") != std::string::npos)
      targets.push_back(i);
  if (targets.empty()) return LLVMFuzzerMutate(data, size, max_size);
  const std::size_t pick = targets[rng() % targets.size()];
  MutateEntry(&entries[pick], &rng);
  const std::string zip = WriteZip(entries);
  if (zip.size() > max_size) return LLVMFuzzerMutate(data, size, max_size);
  std::memcpy(data, zip.data(), zip.size());
  return zip.size();
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data,
                                      std::size_t size) {
  const aia::fuzz::TempFile file(data, size, ".pt");
  try {
    aia::IgbNet::Load(file.path(), "fuzz.yaml", 1, "policy.model");
  } catch (const aia::InputError&) {
  }
  return 0;
}
