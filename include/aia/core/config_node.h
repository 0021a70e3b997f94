// A configuration document as a tree: YAML's structure (scalars, lists,
// mappings) with the line each value came from, and nothing of YAML itself,
// so that every layer can read typed settings from it (core/field_io.h) and
// only the scenario module depends on a YAML library. Values set on the
// command line (`--set key=value`, `--seed`) carry the flag as their origin,
// so that errors about them name the flag instead of a line of the file.
#ifndef AIA_CORE_CONFIG_NODE_H_
#define AIA_CORE_CONFIG_NODE_H_

#include <string>
#include <utility>
#include <vector>

namespace aia {

struct ConfigNode {
  enum class Kind { kNull, kScalar, kList, kMap };
  // How a scalar was written. Only plain scalars may be numbers or booleans,
  // so that `count: "5"` is a string, as YAML means it.
  enum class Style { kPlain, kQuoted, kTagged };

  struct Entry;

  Kind kind = Kind::kNull;
  std::string scalar;  // kScalar: the text as written (unescaped)
  Style style = Style::kPlain;
  std::string tag;  // kTagged: the tag, e.g. "!!float"
  int line = 0;     // 1-based line of the value; 0 when unknown
  // Empty for values from the file; else the command-line flag that set it
  // ("--set", "--seed", ...).
  std::string origin;
  std::vector<ConfigNode> items;  // kList
  std::vector<Entry> entries;     // kMap, in document order

  static ConfigNode Scalar(std::string text, Style style = Style::kPlain);
  static ConfigNode List();
  static ConfigNode Map();

  bool IsNull() const { return kind == Kind::kNull; }
  bool IsScalar() const { return kind == Kind::kScalar; }
  bool IsPlainScalar() const {
    return kind == Kind::kScalar && style == Style::kPlain;
  }
  bool IsList() const { return kind == Kind::kList; }
  bool IsMap() const { return kind == Kind::kMap; }

  // The value under `key` of a mapping, or nullptr.
  const ConfigNode* Find(const std::string& key) const;
  ConfigNode* Find(const std::string& key);
  // Adds (or replaces) the value under `key` of a mapping.
  ConfigNode& Set(const std::string& key, ConfigNode value, int key_line = 0);
  // Removes `key` from a mapping; whether it was there.
  bool Erase(const std::string& key);

  // Marks this node and everything below it as set by `flag`.
  void SetOrigin(const std::string& flag);
};

struct ConfigNode::Entry {
  std::string key;
  int key_line = 0;  // 1-based line of the key
  ConfigNode value;
};

// Whether two trees hold the same value, whatever their lines and origins and
// the order of a mapping's keys (a scalar's text and style count: `5` is not
// `"5"`).
bool SameValue(const ConfigNode& a, const ConfigNode& b);

// The node as it was written, roughly (enough to recognize it in a message):
// `[20, 20]`, `"5"`, `!!float 0.1`, `{a: 1}`; "nothing" for an empty value.
// At most `max_chars` characters ("..." marks a cut).
std::string ShowNode(const ConfigNode& node, std::size_t max_chars = 60);

// "a.b" from "a" and "b" (just "b" at the top), and "a[3]".
std::string ChildKey(const std::string& parent, const std::string& name);
std::string ItemKey(const std::string& list, std::size_t index);

}  // namespace aia

#endif  // AIA_CORE_CONFIG_NODE_H_
