#include "aia/core/config_node.h"

#include <algorithm>

namespace aia {

ConfigNode ConfigNode::Scalar(std::string text, Style style) {
  ConfigNode n;
  n.kind = Kind::kScalar;
  n.scalar = std::move(text);
  n.style = style;
  return n;
}

ConfigNode ConfigNode::List() {
  ConfigNode n;
  n.kind = Kind::kList;
  return n;
}

ConfigNode ConfigNode::Map() {
  ConfigNode n;
  n.kind = Kind::kMap;
  return n;
}

const ConfigNode* ConfigNode::Find(const std::string& key) const {
  for (const Entry& e : entries)
    if (e.key == key) return &e.value;
  return nullptr;
}

ConfigNode* ConfigNode::Find(const std::string& key) {
  for (Entry& e : entries)
    if (e.key == key) return &e.value;
  return nullptr;
}

ConfigNode& ConfigNode::Set(const std::string& key, ConfigNode value,
                            int key_line) {
  kind = Kind::kMap;
  for (Entry& e : entries) {
    if (e.key == key) {
      e.value = std::move(value);
      return e.value;
    }
  }
  entries.push_back({key, key_line, std::move(value)});
  return entries.back().value;
}

bool ConfigNode::Erase(const std::string& key) {
  const auto it = std::find_if(entries.begin(), entries.end(),
                               [&](const Entry& e) { return e.key == key; });
  if (it == entries.end()) return false;
  entries.erase(it);
  return true;
}

bool SameValue(const ConfigNode& a, const ConfigNode& b) {
  if (a.kind != b.kind) return false;
  switch (a.kind) {
    case ConfigNode::Kind::kNull:
      return true;
    case ConfigNode::Kind::kScalar:
      return a.scalar == b.scalar && a.style == b.style && a.tag == b.tag;
    case ConfigNode::Kind::kList:
      if (a.items.size() != b.items.size()) return false;
      for (std::size_t i = 0; i < a.items.size(); ++i)
        if (!SameValue(a.items[i], b.items[i])) return false;
      return true;
    case ConfigNode::Kind::kMap:
      if (a.entries.size() != b.entries.size()) return false;
      for (const ConfigNode::Entry& e : a.entries) {
        const ConfigNode* other = b.Find(e.key);
        if (other == nullptr || !SameValue(e.value, *other)) return false;
      }
      return true;
  }
  return false;
}

void ConfigNode::SetOrigin(const std::string& flag) {
  origin = flag;
  for (ConfigNode& item : items) item.SetOrigin(flag);
  for (Entry& e : entries) e.value.SetOrigin(flag);
}

namespace {

// Appends the node's text to `out`, stopping once `out` is longer than
// `limit` (a document built from aliases can be huge when expanded).
void Render(const ConfigNode& node, std::size_t limit, std::string* out) {
  if (out->size() > limit) return;
  switch (node.kind) {
    case ConfigNode::Kind::kScalar: {
      std::string text;
      for (const char c : node.scalar) {
        if (text.size() > limit) break;
        text += c == '\n' ? std::string("\\n") : std::string(1, c);
      }
      if (node.style == ConfigNode::Style::kPlain) {
        *out += text;
      } else if (node.style == ConfigNode::Style::kTagged) {
        // Explicitly tagged (`!!float 0.1`): say so, since only plain
        // scalars are read as numbers and booleans.
        *out += node.tag + " " + text;
      } else {
        *out += "\"" + text + "\"";
      }
      return;
    }
    case ConfigNode::Kind::kList:
      *out += "[";
      for (std::size_t i = 0; i < node.items.size() && out->size() <= limit;
           ++i) {
        if (i) *out += ", ";
        Render(node.items[i], limit, out);
      }
      *out += "]";
      return;
    case ConfigNode::Kind::kMap:
      *out += "{";
      for (std::size_t i = 0; i < node.entries.size() && out->size() <= limit;
           ++i) {
        if (i) *out += ", ";
        *out += node.entries[i].key + ": ";
        Render(node.entries[i].value, limit, out);
      }
      *out += "}";
      return;
    default:
      *out += "null";
  }
}

}  // namespace

std::string ShowNode(const ConfigNode& node, std::size_t max_chars) {
  if (node.IsNull()) return "nothing";
  std::string text;
  Render(node, max_chars, &text);
  if (text.size() > max_chars) text = text.substr(0, max_chars - 3) + "...";
  return text;
}

std::string ChildKey(const std::string& parent, const std::string& name) {
  return parent.empty() ? name : parent + "." + name;
}

std::string ItemKey(const std::string& list, std::size_t index) {
  return list + "[" + std::to_string(index) + "]";
}

}  // namespace aia
