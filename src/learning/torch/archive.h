// The checks a model or checkpoint file passes before libtorch reads it
// (docs/hardening.md, Fuzzing). libtorch 1.13 trusts its input: it reads
// entries without checking their CRC-32, allocates what an entry's header
// declares, and builds each tensor over its entry's bytes with the size the
// pickle declares, however few bytes the entry holds (an empty entry was a
// crash, an entry 4 bytes short a read past its end). No torch here: zip
// and pickle are read by hand, so that nothing of libtorch runs on a file
// that fails.
#ifndef AIA_SRC_LEARNING_TORCH_ARCHIVE_H_
#define AIA_SRC_LEARNING_TORCH_ARCHIVE_H_

#include <string>

namespace aia {

// Why `bytes` are not a torch archive that aia may hand to libtorch, or "".
// The container: a single-disk, non-zip64 zip whose entries all sit in one
// top folder, each stored (sizes equal) or deflated (at most 64 MiB
// unpacked), unpacking to its declared size and passing its CRC-32, with a
// `version` record this libtorch reads. The tensors: every storage that
// data.pkl and constants.pkl name has its entry (FOLDER/data/KEY), holding
// exactly the bytes its element count and type make, and every tensor's
// offset, sizes and strides stay inside its storage. The message names the
// tensor ("tensor 'fc1.weight' (float32, 128 x 3200) needs 1638400 bytes,
// but its entry 'archive/data/42' holds 0").
std::string ArchiveDamage(const std::string& bytes);

}  // namespace aia

#endif  // AIA_SRC_LEARNING_TORCH_ARCHIVE_H_
