#include "archive.h"

#include <caffe2/serialize/versions.h>
#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string_view>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

namespace aia {
namespace {

// TorchScript code entries are a few KiB; the bound keeps a lying header
// from making libtorch allocate gigabytes (found by fuzzing).
constexpr std::uint32_t kMaxDeflatedEntry = 64u << 20;

// aia's data.pkl is some 4 KiB (a checkpoint's a few times that); the bound
// keeps the check's own values (one per opcode at most) small.
constexpr std::size_t kMaxPickle = 4u << 20;

// Element counts, sizes, strides and offsets beyond this are no tensor of a
// file below 2 GiB (and keep the arithmetic below far from overflow).
constexpr std::int64_t kMaxExtent = std::int64_t{1} << 40;

// A name from the file as a message shows it: printable ASCII, other bytes
// as \xNN, at most `max` characters of it.
std::string Shown(std::string_view name, std::size_t max = 60) {
  std::string out;
  for (std::size_t i = 0; i < name.size() && i < max; ++i) {
    const unsigned char c = static_cast<unsigned char>(name[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    }
  }
  if (name.size() > max) out += "...";
  return out;
}

struct ZipEntry {
  std::string name;
  std::uint32_t method = 0, size = 0, unpacked = 0;
  std::size_t data = 0;  // where its packed bytes start
};

struct Zip {
  std::string folder;  // "archive/"
  std::vector<ZipEntry> entries;
  std::unordered_map<std::string, std::size_t> by_name;
};

// The unpacked bytes of an entry that ZipDamage accepted.
std::string Unpack(const std::string& b, const ZipEntry& e) {
  if (e.method == 0) return b.substr(e.data, e.size);
  std::string out(e.unpacked, '\0');
  z_stream z{};
  if (inflateInit2(&z, -MAX_WBITS) != Z_OK) return "";
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(b.data() + e.data));
  z.avail_in = e.size;
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = e.unpacked;
  inflate(&z, Z_FINISH);
  inflateEnd(&z);
  return out;
}

// Why the data of zip entry `entry` (`size` bytes at `packed`, stored or
// deflated to `unpacked` bytes) does not match its CRC-32, or "".
std::string EntryDataDamage(const std::string& entry, const Bytef* packed,
                            std::uint32_t method, std::uint32_t size,
                            std::uint32_t unpacked, std::uint32_t crc) {
  std::uint32_t got = 0;
  if (method == 0) {  // stored: tensors and pickles
    if (unpacked != size) return entry + " has two different sizes";
    got = static_cast<std::uint32_t>(crc32(0L, packed, size));
  } else if (method == 8) {  // deflated: TorchScript code, a few KiB
    // libtorch allocates the declared size before inflating, so a lying
    // header is checked here first.
    if (unpacked > kMaxDeflatedEntry)
      return entry + " declares " + std::to_string(unpacked) +
             " bytes unpacked (at most " + std::to_string(kMaxDeflatedEntry) +
             ")";
    std::string out(unpacked, '\0');
    z_stream z{};
    if (inflateInit2(&z, -MAX_WBITS) != Z_OK) return "zlib failed";
    z.next_in = const_cast<Bytef*>(packed);
    z.avail_in = size;
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = unpacked;
    const int rc = inflate(&z, Z_FINISH);
    const bool whole = rc == Z_STREAM_END && z.total_out == unpacked;
    inflateEnd(&z);
    if (!whole) return entry + " does not unpack to its declared size";
    got = static_cast<std::uint32_t>(
        crc32(0L, reinterpret_cast<const Bytef*>(out.data()), unpacked));
  } else {
    return entry + " uses compression method " + std::to_string(method) +
           " (model files store or deflate)";
  }
  if (got != crc)
    return entry + " fails its CRC-32 check (the file is damaged)";
  return "";
}

// Why the zip container is not intact, or "" (and *zip lists its entries).
// TorchScript's reader does not check the entries' CRC-32s, and its parser
// crashes on some corrupted code entries (found by fuzzing); a damaged file
// is refused here instead. Torch stores tensors and pickles and deflates
// code: both are unpacked and checked.
std::string ZipDamage(const std::string& b, Zip* zip) {
  const auto u16 = [&](std::size_t at) -> std::uint32_t {
    return static_cast<unsigned char>(b[at]) |
           static_cast<unsigned char>(b[at + 1]) << 8;
  };
  const auto u32 = [&](std::size_t at) -> std::uint32_t {
    return u16(at) | u16(at + 2) << 16;
  };
  // End of central directory: the last "PK\5\6" within 64 KiB of the end.
  if (b.size() < 22) return "not a zip container";
  std::size_t eocd = std::string::npos;
  for (std::size_t i = b.size() - 22 + 1; i-- > 0 && b.size() - i <= 65557;)
    if (u32(i) == 0x06054b50) {
      eocd = i;
      break;
    }
  if (eocd == std::string::npos) return "not a zip container (no directory)";
  const std::uint32_t entries = u16(eocd + 10);
  std::size_t at = u32(eocd + 16);
  if (entries == 0xffff || at == 0xffffffffu)
    return "a zip64 container (model files are far below 4 GiB)";
  // libtorch's reader leaks its zip state when its constructor throws, so
  // what it checks there (entries, one folder, a version record) is checked
  // here first.
  if (entries == 0) return "an empty zip container";
  if (u16(eocd + 4) != 0 || u16(eocd + 6) != 0 || u16(eocd + 8) != entries)
    return "a multi-disk zip container";
  std::string& folder = zip->folder;
  bool has_version = false;
  for (std::uint32_t e = 0; e < entries; ++e) {
    if (at + 46 > b.size() || u32(at) != 0x02014b50 ||
        at + 46 + u16(at + 28) + u16(at + 30) + u16(at + 32) > b.size())
      return "damaged zip directory";
    const std::string_view entry_name(b.data() + at + 46, u16(at + 28));
    if (e == 0) {
      const auto slash = entry_name.find('/');
      if (slash == std::string_view::npos || slash == 0)
        return "not a torch archive (no top folder)";
      folder = entry_name.substr(0, slash + 1);
    }
    // libtorch reads the records under the first entry's folder and
    // ignores the rest: a second folder is not a file it wrote.
    if (entry_name.substr(0, folder.size()) != folder) {
      return "not a torch archive (two top folders, '" +
             Shown(std::string_view(folder).substr(0, folder.size() - 1)) +
             "' and '" + Shown(entry_name.substr(0, entry_name.find('/'))) +
             "')";
    }
    const bool is_version = entry_name.size() == folder.size() + 7 &&
                            entry_name.substr(folder.size()) == "version";
    const std::uint32_t method = u16(at + 10), crc = u32(at + 16),
                        size = u32(at + 20), unpacked = u32(at + 24),
                        name = u16(at + 28), extra = u16(at + 30),
                        comment = u16(at + 32), local = u32(at + 42);
    const std::string entry = "zip entry " + std::to_string(e);
    if (std::size_t{local} + 30 > b.size() || u32(local) != 0x04034b50)
      return "damaged " + entry;
    const std::size_t data =
        std::size_t{local} + 30 + u16(local + 26) + u16(local + 28);
    if (data + size > b.size()) return entry + " is cut short";
    const auto* packed = reinterpret_cast<const Bytef*>(b.data() + data);
    if (std::string why =
            EntryDataDamage(entry, packed, method, size, unpacked, crc);
        !why.empty())
      return why;
    if (is_version) {  // a small number in the range this libtorch reads
      char* end = nullptr;
      const std::string text = method == 0 ? b.substr(data, size) : "";
      const long version = std::strtol(text.c_str(), &end, 10);
      if (text.empty() || text.size() > 4 ||
          version < static_cast<long>(
                        caffe2::serialize::kMinSupportedFileFormatVersion) ||
          version > static_cast<long>(
                        caffe2::serialize::kMaxSupportedFileFormatVersion) ||
          (*end != '\0' && *end != '\n'))
        return "not a torch archive (version record '" + Shown(text, 8) + "')";
      has_version = true;
    }
    ZipEntry z;
    z.name = std::string(entry_name);
    z.method = method;
    z.size = size;
    z.unpacked = unpacked;
    z.data = data;
    if (!zip->by_name.emplace(z.name, zip->entries.size()).second)
      return "not a torch archive (two entries named '" + Shown(z.name) + "')";
    zip->entries.push_back(std::move(z));
    at += 46 + name + extra + comment;
  }
  if (!has_version) return "not a torch archive (no version record)";
  return "";
}

// --- The pickles ---------------------------------------------------------

// A value of the pickle machine, as far as the check needs it.
struct PValue {
  enum class Kind : std::uint8_t {
    kNone,
    kInt,
    kText,
    kTuple,
    kList,
    kDict,
    kGlobal,
    kStorage,
    kTensor,
    kObject,
    kOther,
  };
  Kind kind = Kind::kNone;
  std::int64_t number = 0;  // kInt; kStorage: its element count
  std::string text;         // kText; kGlobal "module.name"; kStorage its key
  // kTuple, kList; kDict: key, value, key, value, ...; kObject: its state;
  // kTensor: its storage.
  std::vector<std::shared_ptr<PValue>> items;
  int tensor = -1;  // kTensor: its index among the pickle's tensors
  // kStorage: what is wrong with it ("" when nothing), its element type and
  // size.
  std::string problem, dtype;
  int itemsize = 0;
};
using PRef = std::shared_ptr<PValue>;

struct StorageType {
  const char* global;
  const char* dtype;
  int itemsize;
};
constexpr StorageType kStorageTypes[] = {
    {"torch.FloatStorage", "float32", 4},
    {"torch.DoubleStorage", "float64", 8},
    {"torch.HalfStorage", "float16", 2},
    {"torch.BFloat16Storage", "bfloat16", 2},
    {"torch.LongStorage", "int64", 8},
    {"torch.IntStorage", "int32", 4},
    {"torch.ShortStorage", "int16", 2},
    {"torch.CharStorage", "int8", 1},
    {"torch.ByteStorage", "uint8", 1},
    {"torch.BoolStorage", "bool", 1},
    {"torch.ComplexFloatStorage", "complex64", 8},
    {"torch.ComplexDoubleStorage", "complex128", 16},
};

// A tensor the pickle builds, with what is wrong with it.
struct TensorUse {
  PRef storage;
  std::vector<std::int64_t> sizes;
  std::string problem;  // its own (its extent); the storage's is apart
  std::string name;     // its attribute path, found after the pickle ran
};

// Runs one pickle (data.pkl or constants.pkl) far enough to see every
// storage it names and every tensor it builds, and checks them against the
// archive's entries.
class PickleCheck {
 public:
  PickleCheck(const std::string& bytes, const Zip& zip,
              const std::string& pickle, std::string tensor_dir)
      : bytes_(bytes),
        zip_(zip),
        pickle_(pickle),
        tensor_dir_(std::move(tensor_dir)) {}

  // "" or the first problem.
  std::string Run() {
    const auto it = zip_.by_name.find(zip_.folder + pickle_);
    if (it == zip_.by_name.end()) return "";  // libtorch says what is missing
    const ZipEntry& entry = zip_.entries[it->second];
    if (entry.unpacked > kMaxPickle)
      return "its " + pickle_ + " holds " + std::to_string(entry.unpacked) +
             " bytes (aia's hold a few KiB; at most " +
             std::to_string(kMaxPickle) + ")";
    data_ = Unpack(bytes_, entry);
    PRef root;
    try {
      root = Execute();
    } catch (const Bad& bad) {
      return "its " + pickle_ + " " + bad.what;
    }
    // libtorch takes data.pkl's value for the module and asserts that it
    // is one (its own "INTERNAL ASSERT FAILED ... please report a bug").
    if (pickle_ == "data.pkl" && root->kind != PValue::Kind::kObject)
      return "its data.pkl holds " + KindName(root->kind) +
             ", not a module (not a model file torch wrote)";
    NameTensors(root);
    for (const TensorUse& t : tensors_) {
      const std::string& problem =
          t.storage->problem.empty() ? t.problem : t.storage->problem;
      if (problem.empty()) continue;
      std::string shape;
      for (std::size_t i = 0; i < t.sizes.size(); ++i)
        shape += (i ? " x " : "") + std::to_string(t.sizes[i]);
      return "tensor '" +
             (t.name.empty() ? "(in " + pickle_ + ")" : Shown(t.name, 80)) +
             "' (" + t.storage->dtype + (shape.empty() ? "" : ", " + shape) +
             ") " + problem;
    }
    for (const PRef& s : storages_)
      if (!s->problem.empty())
        return "storage '" + Shown(s->text, 40) + "' of " + pickle_ + " " +
               s->problem;
    return "";
  }

 private:
  struct Bad {
    std::string what;
  };
  [[noreturn]] static void Fail(const std::string& what) { throw Bad{what}; }

  // What a value of each kind is, in PValue::Kind's order.
  static std::string KindName(PValue::Kind kind) {
    static constexpr const char* kNames[] = {"None",
                                             "a number",
                                             "a string",
                                             "a tuple",
                                             "a list",
                                             "a dict",
                                             "a class or function",
                                             "a storage",
                                             "a tensor",
                                             "a module",
                                             "a value"};
    static_assert(std::size(kNames) ==
                  static_cast<std::size_t>(PValue::Kind::kOther) + 1);
    return kNames[static_cast<int>(kind)];
  }

  const char* Take(std::size_t n) {
    if (n > data_.size() - at_) Fail("ends early (the file is cut)");
    const char* p = data_.data() + at_;
    at_ += n;
    return p;
  }
  std::uint64_t Unsigned(std::size_t n) {
    const unsigned char* p = reinterpret_cast<const unsigned char*>(Take(n));
    std::uint64_t v = 0;
    for (std::size_t i = n; i-- > 0;) v = v << 8 | p[i];
    return v;
  }
  std::string Line() {
    const std::size_t nl = data_.find('\n', at_);
    if (nl == std::string::npos) Fail("ends early (the file is cut)");
    std::string line = data_.substr(at_, nl - at_);
    at_ = nl + 1;
    return line;
  }

  static PRef Make(PValue::Kind kind) {
    auto v = std::make_shared<PValue>();
    v->kind = kind;
    return v;
  }
  PRef Pop() {
    if (stack_.size() <= Floor()) Fail("pops an empty stack (not a pickle)");
    PRef v = std::move(stack_.back());
    stack_.pop_back();
    return v;
  }
  PRef& Top() {
    if (stack_.size() <= Floor()) Fail("reads an empty stack (not a pickle)");
    return stack_.back();
  }
  std::size_t Floor() const { return marks_.empty() ? 0 : marks_.back(); }
  // The values pushed since the last MARK, which is removed.
  std::vector<PRef> PopMark() {
    if (marks_.empty()) Fail("has no MARK where one is needed (not a pickle)");
    const std::size_t mark = marks_.back();
    marks_.pop_back();
    std::vector<PRef> items(std::make_move_iterator(stack_.begin() + mark),
                            std::make_move_iterator(stack_.end()));
    stack_.resize(mark);
    return items;
  }
  void Push(PRef v) { stack_.push_back(std::move(v)); }
  PRef Text(std::string s) {
    PRef v = Make(PValue::Kind::kText);
    v->text = std::move(s);
    return v;
  }
  PRef Int(std::int64_t n) {
    PRef v = Make(PValue::Kind::kInt);
    v->number = n;
    return v;
  }
  PRef Sequence(PValue::Kind kind, std::vector<PRef> items) {
    PRef v = Make(kind);
    v->items = std::move(items);
    return v;
  }
  PRef Memo(std::uint64_t key) {
    const auto it = memo_.find(key);
    if (it == memo_.end()) Fail("reads a memo entry it never wrote");
    return it->second;
  }
  // torch writes memo entries 0, 1, 2, ... and libtorch's reader appends
  // each one whatever its number says (after reserving room for twice that
  // number: 4 bytes of a damaged pickle asked for 70 GB, found by fuzzing),
  // so any other number is refused.
  void Remember(std::uint64_t key) {
    if (key != memo_.size())
      Fail("writes memo entry " + std::to_string(key) + " where entry " +
           std::to_string(memo_.size()) + " comes next (the file is damaged)");
    memo_[key] = Top();
  }

  PRef Execute() {
    while (true) {
      const unsigned char op = static_cast<unsigned char>(*Take(1));
      switch (op) {
        case 0x80:  // PROTO
          Take(1);
          break;
        case 0x95:  // FRAME
          Take(8);
          break;
        case '.': {  // STOP
          PRef result = Pop();
          return result;
        }
        case '(':  // MARK
          marks_.push_back(stack_.size());
          break;
        case '0':  // POP
          Pop();
          break;
        case '1':  // POP_MARK
          PopMark();
          break;
        case '2':  // DUP
          Push(Top());
          break;
        case 'N':  // NONE
          Push(Make(PValue::Kind::kNone));
          break;
        case 0x88:  // NEWTRUE
        case 0x89:  // NEWFALSE
          Push(Int(op == 0x88 ? 1 : 0));
          break;
        case 'J':  // BININT
          Push(Int(static_cast<std::int32_t>(Unsigned(4))));
          break;
        case 'K':  // BININT1
          Push(Int(static_cast<std::int64_t>(Unsigned(1))));
          break;
        case 'M':  // BININT2
          Push(Int(static_cast<std::int64_t>(Unsigned(2))));
          break;
        case 0x8a: {  // LONG1: little-endian two's complement
          const std::size_t n = Unsigned(1);
          if (n > 8) Fail("holds an integer beyond 64 bits");
          std::uint64_t v = n ? Unsigned(n) : 0;
          if (n > 0 && n < 8 && (v >> (8 * n - 1)) != 0)
            v |= ~std::uint64_t{0} << (8 * n);  // sign-extended
          Push(Int(static_cast<std::int64_t>(v)));
          break;
        }
        case 'G':  // BINFLOAT
          Take(8);
          Push(Make(PValue::Kind::kOther));
          break;
        case 'X': {  // BINUNICODE
          const std::size_t n = Unsigned(4);
          Push(Text(std::string(Take(n), n)));
          break;
        }
        case 0x8c: {  // SHORT_BINUNICODE
          const std::size_t n = Unsigned(1);
          Push(Text(std::string(Take(n), n)));
          break;
        }
        case 0x8d: {  // BINUNICODE8
          const std::uint64_t n = Unsigned(8);
          if (n > data_.size()) Fail("ends early (the file is cut)");
          Push(Text(std::string(Take(n), n)));
          break;
        }
        case 'T':    // BINSTRING
        case 'B': {  // BINBYTES
          const std::size_t n = Unsigned(4);
          Push(Text(std::string(Take(n), n)));
          break;
        }
        case 'U':    // SHORT_BINSTRING
        case 'C': {  // SHORT_BINBYTES
          const std::size_t n = Unsigned(1);
          Push(Text(std::string(Take(n), n)));
          break;
        }
        case ')':  // EMPTY_TUPLE
          Push(Make(PValue::Kind::kTuple));
          break;
        case 't':  // TUPLE
          Push(Sequence(PValue::Kind::kTuple, PopMark()));
          break;
        case 0x85:    // TUPLE1
        case 0x86:    // TUPLE2
        case 0x87: {  // TUPLE3
          std::vector<PRef> items(op - 0x84);
          for (std::size_t i = items.size(); i-- > 0;) items[i] = Pop();
          Push(Sequence(PValue::Kind::kTuple, std::move(items)));
          break;
        }
        case ']':  // EMPTY_LIST
          Push(Make(PValue::Kind::kList));
          break;
        case 'l':  // LIST
          Push(Sequence(PValue::Kind::kList, PopMark()));
          break;
        case 'a': {  // APPEND
          PRef v = Pop();
          Top()->items.push_back(std::move(v));
          break;
        }
        case 'e': {  // APPENDS
          std::vector<PRef> items = PopMark();
          PRef& list = Top();
          for (PRef& v : items) list->items.push_back(std::move(v));
          break;
        }
        case '}':  // EMPTY_DICT
          Push(Make(PValue::Kind::kDict));
          break;
        case 'd': {  // DICT
          std::vector<PRef> items = PopMark();
          if (items.size() % 2 != 0) Fail("holds a key without a value");
          Push(Sequence(PValue::Kind::kDict, std::move(items)));
          break;
        }
        case 's': {  // SETITEM
          PRef value = Pop();
          PRef key = Pop();
          PRef& dict = Top();
          dict->items.push_back(std::move(key));
          dict->items.push_back(std::move(value));
          break;
        }
        case 'u': {  // SETITEMS
          std::vector<PRef> items = PopMark();
          if (items.size() % 2 != 0) Fail("holds a key without a value");
          PRef& dict = Top();
          for (PRef& v : items) dict->items.push_back(std::move(v));
          break;
        }
        case 'q':  // BINPUT
          Remember(Unsigned(1));
          break;
        case 'r':  // LONG_BINPUT
          Remember(Unsigned(4));
          break;
        case 0x94:  // MEMOIZE
          Remember(memo_.size());
          break;
        case 'h':  // BINGET
          Push(Memo(Unsigned(1)));
          break;
        case 'j':  // LONG_BINGET
          Push(Memo(Unsigned(4)));
          break;
        case 'c': {  // GLOBAL
          std::string module = Line();
          std::string name = Line();
          PRef g = Make(PValue::Kind::kGlobal);
          g->text = module + "." + name;
          Push(std::move(g));
          break;
        }
        case 0x93: {  // STACK_GLOBAL
          PRef name = Pop();
          PRef module = Pop();
          PRef g = Make(PValue::Kind::kGlobal);
          g->text = module->text + "." + name->text;
          Push(std::move(g));
          break;
        }
        case 0x81: {  // NEWOBJ
          Pop();      // its arguments
          PRef cls = Pop();
          PRef object = Make(PValue::Kind::kObject);
          object->text = cls->text;
          Push(std::move(object));
          break;
        }
        case 'b': {  // BUILD
          PRef state = Pop();
          PRef& object = Top();
          if (object->kind == PValue::Kind::kObject)
            object->items.assign(1, std::move(state));
          break;
        }
        case 'R': {  // REDUCE
          PRef args = Pop();
          PRef callable = Pop();
          Push(Reduce(*callable, args));
          break;
        }
        case 'Q':  // BINPERSID
          Push(Storage(Pop()));
          break;
        default: {
          char code[8];
          std::snprintf(code, sizeof code, "0x%02x", op);
          Fail("uses pickle opcode " + std::string(code) + " at byte " +
               std::to_string(at_ - 1) +
               ", which torch's model files do not (the file is damaged)");
        }
      }
    }
  }

  // ('storage', torch.XStorage, key, location, numel): the storage and
  // whether its entry holds exactly its bytes.
  PRef Storage(const PRef& id) {
    const std::vector<PRef>& a = id->items;
    if (id->kind != PValue::Kind::kTuple || a.size() < 5 ||
        a[0]->kind != PValue::Kind::kText || a[0]->text != "storage" ||
        a[1]->kind != PValue::Kind::kGlobal ||
        a[2]->kind != PValue::Kind::kText || a[4]->kind != PValue::Kind::kInt)
      Fail("names a storage in a form torch does not write");
    const StorageType* type = nullptr;
    for (const StorageType& t : kStorageTypes)
      if (a[1]->text == t.global) type = &t;
    if (!type)
      Fail("names a storage of type '" + Shown(a[1]->text) +
           "', which aia's models do not hold");
    PRef s = Make(PValue::Kind::kStorage);
    s->text = a[2]->text;
    s->number = a[4]->number;
    s->dtype = type->dtype;
    s->itemsize = type->itemsize;
    storages_.push_back(s);
    if (s->number < 0 || s->number > kMaxExtent) {
      s->problem = "declares " + std::to_string(s->number) + " elements";
      return s;
    }
    if (s->number == 0) return s;  // libtorch reads no entry
    const std::string entry = zip_.folder + tensor_dir_ + s->text;
    const auto it = zip_.by_name.find(entry);
    const std::int64_t need = s->number * type->itemsize;
    if (it == zip_.by_name.end()) {
      s->problem = "needs " + std::to_string(need) + " bytes from entry '" +
                   Shown(entry, 80) + "', which is missing";
    } else if (const std::int64_t holds = zip_.entries[it->second].unpacked;
               holds != need) {
      s->problem = "needs " + std::to_string(need) + " bytes (" +
                   std::to_string(s->number) + " x " + type->dtype +
                   "), but its entry '" + Shown(entry, 80) + "' holds " +
                   std::to_string(holds) +
                   (holds < need ? " (the file is damaged or cut)"
                                 : " (the file is damaged)");
    }
    return s;
  }

  PRef Reduce(const PValue& callable, const PRef& args) {
    const std::string& f = callable.text;
    if (callable.kind != PValue::Kind::kGlobal)
      return Make(PValue::Kind::kOther);
    if (f == "torch._utils._rebuild_tensor_v2") return Tensor(args);
    if (f.rfind("torch._utils._rebuild", 0) == 0)
      Fail("rebuilds a tensor with " + Shown(f) +
           ", which aia's models do not hold");
    if (f == "collections.OrderedDict") return Make(PValue::Kind::kDict);
    // torch.jit._pickle's typed lists and type tags wrap their first
    // argument.
    if (f.rfind("torch.jit._pickle.", 0) == 0 && !args->items.empty())
      return args->items[0];
    return Make(PValue::Kind::kOther);
  }

  // (storage, offset, sizes, strides, ...): every element it can reach must
  // lie inside the storage.
  PRef Tensor(const PRef& args) {
    const std::vector<PRef>& a = args->items;
    if (args->kind != PValue::Kind::kTuple || a.size() < 4 ||
        a[0]->kind != PValue::Kind::kStorage ||
        a[1]->kind != PValue::Kind::kInt ||
        a[2]->kind != PValue::Kind::kTuple ||
        a[3]->kind != PValue::Kind::kTuple ||
        a[2]->items.size() != a[3]->items.size() || a[2]->items.size() > 64)
      Fail("builds a tensor in a form torch does not write");
    TensorUse use;
    use.storage = a[0];
    const std::int64_t offset = a[1]->number;
    bool empty = false, sane = offset >= 0 && offset <= kMaxExtent;
    std::int64_t last = offset;
    for (std::size_t i = 0; i < a[2]->items.size(); ++i) {
      const PValue& size = *a[2]->items[i];
      const PValue& stride = *a[3]->items[i];
      if (size.kind != PValue::Kind::kInt || stride.kind != PValue::Kind::kInt)
        Fail("builds a tensor in a form torch does not write");
      use.sizes.push_back(size.number);
      if (size.number < 0 || size.number > kMaxExtent || stride.number < 0 ||
          stride.number > kMaxExtent) {
        sane = false;
        continue;
      }
      if (size.number == 0) empty = true;
      // At most 64 terms below 2^80 each: exact in 128 bits, then bounded.
      const __int128 reach =
          static_cast<__int128>(size.number - 1) * stride.number + last;
      last = reach > kMaxExtent ? kMaxExtent + 1
                                : static_cast<std::int64_t>(reach);
    }
    if (!sane) {
      use.problem = "has a negative or impossibly large offset, size or stride";
    } else if (!empty && last >= use.storage->number &&
               use.storage->problem.empty()) {
      use.problem = "reaches element " + std::to_string(last) +
                    " of a storage of " + std::to_string(use.storage->number) +
                    " elements (its sizes, strides or offset are damaged)";
    }
    PRef t = Make(PValue::Kind::kTensor);
    t->items.push_back(use.storage);
    t->tensor = static_cast<int>(tensors_.size());
    tensors_.push_back(std::move(use));
    return t;
  }

  // Each tensor's path of attribute names from the root ("blocks.0.conv1.
  // weight"), the first path found; every value is visited once.
  void NameTensors(const PRef& root) {
    std::vector<std::pair<const PValue*, std::string>> todo = {
        {root.get(), ""}};
    std::unordered_set<const PValue*> seen;
    while (!todo.empty()) {
      auto [v, path] = std::move(todo.back());
      todo.pop_back();
      if (!v || !seen.insert(v).second) continue;
      switch (v->kind) {
        case PValue::Kind::kTensor:
          if (tensors_[v->tensor].name.empty()) tensors_[v->tensor].name = path;
          break;
        case PValue::Kind::kObject:
          for (const PRef& s : v->items) todo.emplace_back(s.get(), path);
          break;
        case PValue::Kind::kDict:
          for (std::size_t i = v->items.size(); i >= 2; i -= 2) {
            const PValue& key = *v->items[i - 2];
            const std::string name =
                key.kind == PValue::Kind::kText ? key.text : "?";
            todo.emplace_back(v->items[i - 1].get(),
                              path.empty() ? name : path + "." + name);
          }
          break;
        case PValue::Kind::kTuple:
        case PValue::Kind::kList:
          for (std::size_t i = v->items.size(); i-- > 0;)
            todo.emplace_back(v->items[i].get(),
                              path + "[" + std::to_string(i) + "]");
          break;
        default:
          break;
      }
    }
  }

  const std::string& bytes_;
  const Zip& zip_;
  const std::string pickle_, tensor_dir_;
  std::string data_;
  std::size_t at_ = 0;
  std::vector<PRef> stack_;
  std::vector<std::size_t> marks_;
  std::unordered_map<std::uint64_t, PRef> memo_;
  std::vector<PRef> storages_;
  std::vector<TensorUse> tensors_;
};

}  // namespace

std::string ArchiveDamage(const std::string& bytes) {
  Zip zip;
  if (std::string damage = ZipDamage(bytes, &zip); !damage.empty())
    return damage;
  // libtorch reads the module's state from data.pkl (tensors in data/) and
  // its constants from constants.pkl (tensors in constants/).
  for (const auto& [pickle, dir] :
       {std::pair<const char*, const char*>{"data.pkl", "data/"},
        {"constants.pkl", "constants/"}}) {
    if (std::string damage = PickleCheck(bytes, zip, pickle, dir).Run();
        !damage.empty())
      return damage;
  }
  return "";
}

}  // namespace aia
