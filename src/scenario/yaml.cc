#include "aia/scenario/yaml.h"

#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <cctype>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include "aia/core/error.h"
#include "aia/core/field_io.h"

namespace aia {
namespace {

// More values than this is not a scenario (5000 explicit boxes or targets
// take some 50 000): a few nested YAML aliases expand to billions of nodes.
constexpr long kMaxNodes = 200000;

// Nesting deeper than this is not a scenario, and a recursive alias
// (`&a [*a]`) would otherwise recurse until the stack overflows.
constexpr int kMaxDepth = 64;

// yaml-cpp 0.7's parser stops consuming its input on some stray tokens (a
// ',' outside brackets: ",", "[],", "!,", "- a\n,", and more that fuzzing
// keeps finding) and then hands out the same empty document again and again;
// YAML::LoadAll collects them until memory runs out (upstream yaml-cpp
// #1040, fixed after 0.7). So documents are walked here with a parser of our
// own that stops at the first one that starts where the last one did: that
// place is reported.
//
// The same pass counts the values as the parser reads them, so that a
// document of millions of keys is refused after kMaxNodes of them, before
// yaml-cpp builds its tree (some 1 KiB per value: 1.2 million keys took 1.2
// GB and 80 s).
class DocumentStarts : public YAML::EventHandler {
 public:
  // Thrown when the document holds more than kMaxNodes values.
  struct TooManyValues {
    YAML::Mark mark;
  };
  // Thrown at a quoted scalar that does not end on the line it starts on.
  // YAML lets a quoted value run over lines, so a missing closing quote
  // takes every line after it, keys and all, into one string (yaml-cpp
  // complains only where the text has no last newline); a scenario's
  // values are short, so one that runs over lines is refused instead.
  struct OpenQuote {
    YAML::Mark mark;
  };

  explicit DocumentStarts(const std::string& text) : text_(text) {}

  YAML::Mark start;
  void OnDocumentStart(const YAML::Mark& mark) override {
    start = mark;
    values_ = 0;
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override { Count(mark); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { Count(mark); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                const std::string&) override {
    Count(mark);
    CheckQuoteEnds(mark);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&,
                       YAML::anchor_t, YAML::EmitterStyle::value) override {
    Count(mark);
  }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {
    Count(mark);
  }
  void OnMapEnd() override {}

 private:
  void Count(const YAML::Mark& mark) {
    if (++values_ > kMaxNodes) throw TooManyValues{mark};
  }
  // A scalar starting with a quote must have its closing quote before the
  // end of its line (a double-quoted one skips backslash escapes; in a
  // single-quoted one '' is a quote).
  void CheckQuoteEnds(const YAML::Mark& mark) const {
    if (mark.pos < 0) return;
    std::size_t i = static_cast<std::size_t>(mark.pos);
    if (i >= text_.size() || (text_[i] != '"' && text_[i] != '\'')) return;
    const char quote = text_[i];
    for (++i; i < text_.size() && text_[i] != '\n' && text_[i] != '\r'; ++i) {
      if (quote == '"' && text_[i] == '\\') {
        ++i;
      } else if (text_[i] == quote) {
        if (quote == '\'' && i + 1 < text_.size() && text_[i + 1] == '\'') {
          ++i;
        } else {
          return;
        }
      }
    }
    throw OpenQuote{mark};
  }
  const std::string& text_;
  long values_ = 0;
};

std::string OpenQuoteMessage(const YAML::Mark& mark) {
  return "the quoted value at column " + std::to_string(mark.column + 1) +
         " does not end on its line (a missing closing quote?); a quoted "
         "value must end on the line it starts on";
}

struct Documents {
  int count = 0;
  int second_line = 0;  // 1-based line where the second one starts
};

// Throws YAML::ParserException where the parser stops making progress.
Documents CountDocuments(const std::string& text) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  DocumentStarts handler(text);
  Documents docs;
  int last = -1;
  while (parser.HandleNextDocument(handler)) {
    const YAML::Mark& at = handler.start;
    if (at.pos <= last) {
      const std::size_t pos = static_cast<std::size_t>(at.pos);
      throw YAML::ParserException(at,
                                  pos < text.size() && text[pos] == ','
                                      ? "unexpected ','"
                                      : "the parser cannot go on from here");
    }
    last = at.pos;
    if (++docs.count == 2) docs.second_line = at.line + 1;
  }
  return docs;
}

// yaml-cpp marks an empty value (`key:`) at the next token, often on a later
// line, so an empty value is blamed on the line of its key instead.
int LineOf(const YAML::Node& node, int fallback) {
  if (node.IsNull() || node.Mark().line < 0) return fallback;
  return node.Mark().line + 1;
}

class Converter {
 public:
  Converter(std::string file, std::string origin)
      : file_(std::move(file)), origin_(std::move(origin)) {}

  ConfigNode Convert(const YAML::Node& node, const std::string& key,
                     int fallback_line) {
    struct Depth {
      explicit Depth(int* d) : d_(d) { ++*d_; }
      ~Depth() { --*d_; }
      int* d_;
    } depth(&depth_);
    if (depth_ > kMaxDepth) {
      // The key down to the first list level (not 64 of them).
      const std::string top = key.substr(0, key.find('['));
      Fail(LineOf(node, fallback_line), top.empty() ? "(yaml)" : top,
           "nests deeper than " + std::to_string(kMaxDepth) +
               " levels (a recursive alias such as &a [*a]?)");
    }
    if (++count_ > kMaxNodes) {
      Fail(0, "(yaml)",
           "the document holds more than " + std::to_string(kMaxNodes) +
               " values (aliases expanded); a scenario is far smaller");
    }
    ConfigNode out;
    out.line = LineOf(node, fallback_line);
    out.origin = origin_;
    CheckTag(node, key, out.line);
    switch (node.Type()) {
      case YAML::NodeType::Scalar: {
        out.kind = ConfigNode::Kind::kScalar;
        out.scalar = node.Scalar();
        // Plain scalars get the tag "?", quoted ones "!".
        const std::string& tag = node.Tag();
        if (tag == "?" || tag.empty()) {
          out.style = ConfigNode::Style::kPlain;
        } else if (tag == "!") {
          out.style = ConfigNode::Style::kQuoted;
        } else {
          out.style = ConfigNode::Style::kTagged;
          const std::string core = "tag:yaml.org,2002:";
          out.tag =
              tag.rfind(core, 0) == 0 ? "!!" + tag.substr(core.size()) : tag;
          // `!!int 3`, `!!float 0.1`, `!!bool true`: the value the tag says,
          // read as the plain scalar it is; a text the tag does not fit is
          // refused here, not read as another type.
          if (out.tag == "!!int" || out.tag == "!!float" ||
              out.tag == "!!bool") {
            const std::string& s = out.scalar;
            const bool fits =
                out.tag == "!!int"     ? field_text::IsIntegerLiteral(s)
                : out.tag == "!!float" ? field_text::IsDecimalLiteral(s)
                                       : s == "true" || s == "false";
            if (!fits)
              Fail(out.line, key.empty() ? "(document)" : key,
                   "'" + (s.size() > 40 ? s.substr(0, 40) + "..." : s) +
                       "' is not " +
                       (out.tag == "!!int"     ? "an integer"
                        : out.tag == "!!float" ? "a decimal number"
                                               : "true or false") +
                       ", as its tag " + out.tag + " says");
            const bool float_tag = out.tag == "!!float";
            out.style = ConfigNode::Style::kPlain;
            out.tag.clear();
            // `!!float 12` is the decimal 12.0, not the integer 12: an
            // integer key refuses it, as it refuses 12.0.
            if (float_tag && field_text::IsIntegerLiteral(s))
              out.scalar += ".0";
          }
        }
        break;
      }
      case YAML::NodeType::Sequence:
        out.kind = ConfigNode::Kind::kList;
        for (std::size_t i = 0; i < node.size(); ++i)
          out.items.push_back(Convert(node[i], ItemKey(key, i), out.line));
        break;
      case YAML::NodeType::Map: {
        out.kind = ConfigNode::Kind::kMap;
        // The keys seen, with their lines: a duplicate is found in constant
        // time (comparing each key with all before it made 100 000 keys
        // take 12 s).
        std::unordered_map<std::string, int> seen;
        for (const auto& kv : node) {
          // A null key (`~: 3`) has no mark of its own: its value's line.
          const int key_line = LineOf(kv.first, LineOf(kv.second, out.line));
          if (!kv.first.IsScalar()) {
            ConfigNode shown = Convert(kv.first, key, key_line);
            Fail(key_line, key.empty() ? "(document)" : key,
                 "keys must be names, got " + ShowNode(shown));
          }
          const std::string name = kv.first.Scalar();
          const std::string child = ChildKey(key, name);
          CheckTag(kv.first, child, key_line);
          const auto [at, fresh] = seen.emplace(name, key_line);
          if (!fresh) {
            Fail(key_line, child,
                 "duplicate key (first given at line " +
                     std::to_string(at->second) + "); give each key once");
          }
          out.entries.push_back(
              {name, key_line, Convert(kv.second, child, key_line)});
        }
        break;
      }
      default:
        out.kind = ConfigNode::Kind::kNull;
    }
    return out;
  }

 private:
  // YAML's own tags are read (`!!str 5` is a string, `!!int 5` the integer;
  // Convert checks that the text fits the tag); any other tag (`!foo`,
  // `!<tag:x>`) means something aia does not know: refused rather than
  // dropped.
  void CheckTag(const YAML::Node& node, const std::string& key,
                int line) const {
    const std::string& tag = node.Tag();
    if (tag.empty() || tag == "?" || tag == "!") return;
    const std::string core = "tag:yaml.org,2002:";
    const std::string type =
        tag.rfind(core, 0) == 0 ? tag.substr(core.size()) : "";
    const bool ok = node.IsMap()        ? type == "map"
                    : node.IsSequence() ? type == "seq"
                    : node.IsNull()
                        ? type == "null" || type == "str"
                        : type == "str" || type == "int" || type == "float" ||
                              type == "bool" || type == "null";
    if (ok) return;
    const std::string shown = !type.empty()   ? "!!" + type
                              : tag[0] == '!' ? tag
                                              : "!<" + tag + ">";
    Fail(line, key.empty() ? "(document)" : key,
         "the YAML tag `" +
             (shown.size() > 40 ? shown.substr(0, 40) + "..." : shown) +
             "` is not one aia reads (only YAML's own !!str, !!int, "
             "!!float, !!bool, !!null, !!map and !!seq); remove it");
  }

  [[noreturn]] void Fail(int line, const std::string& key,
                         const std::string& what) const {
    // A --set value's key under the path it was given for (--set
    // robots.count for a duplicate inside `robots={count: 2, count: 3}`).
    if (!origin_.empty())
      throw InputError::Flag(
          key.empty() || key[0] == '(' ? origin_ : origin_ + " " + key, what);
    throw InputError(file_, line, key, what);
  }

  std::string file_, origin_;
  long count_ = 0;
  int depth_ = 0;
};

// yaml-cpp's message where it stops at a stray ',' ("end of map not found")
// is replaced by what is there.
// Its "illegal map value" after a key of more than 1024 characters (YAML's
// limit for an implicit key) says why.
std::string YamlMessage(const YAML::Exception& e, const std::string& text) {
  const auto pos = static_cast<std::size_t>(e.mark.pos);
  if (e.mark.pos >= 0 && pos < text.size() && text[pos] == ',')
    return "unexpected ','";
  if (e.msg == YAML::ErrorMsg::MAP_VALUE && e.mark.pos >= 0 &&
      pos < text.size() && text[pos] == ':') {
    const std::size_t newline = text.rfind('\n', pos);
    const std::size_t line_start =
        newline == std::string::npos ? 0 : newline + 1;
    if (pos - line_start > 1024) {
      return e.msg +
             " (a key of more than 1024 characters? YAML allows no longer "
             "key unless it is written as `? KEY`)";
    }
  }
  return e.msg;
}

// What a document of too many values or too deep a nesting gets, found
// while the parser reads it (its line and column).
std::string TooManyValuesMessage() {
  return "the document holds more than " + std::to_string(kMaxNodes) +
         " values; a scenario is far smaller";
}
std::string TooDeepMessage(const YAML::Mark& mark) {
  // yaml-cpp stops at its own depth limit with "bad file".
  return "nests deeper than " + std::to_string(kMaxDepth) + " levels" +
         (mark.column >= 0 ? " (column " + std::to_string(mark.column + 1) + ")"
                           : std::string());
}

InputError YamlError(const YAML::Exception& e, const std::string& file,
                     const std::string& text) {
  const bool has_mark = e.mark.line >= 0;
  return InputError(
      file, has_mark ? e.mark.line + 1 : 0, "(yaml)",
      "invalid YAML: " + YamlMessage(e, text) +
          (has_mark ? " (column " + std::to_string(e.mark.column + 1) + ")"
                    : ""));
}

// --- Emitting --------------------------------------------------------------

constexpr std::size_t kLineWidth = 80;

// Numbers as the readers parse them (core/field_io.h), and YAML's words.
bool LooksLikeNumberOrWord(const std::string& s) {
  return field_text::ParseReal(ConfigNode::Scalar(s)).has_value() ||
         field_text::IsYamlWord(s);
}

// Whether a string can be written without quotes and read back as itself.
bool SafePlain(const std::string& s) {
  if (s.empty() || s.front() == ' ' || s.back() == ' ') return false;
  const char first = s.front();
  if (!(std::isalnum(static_cast<unsigned char>(first)) || first == '_' ||
        first == '/' || first == '.'))
    return false;
  for (const char c : s) {
    const bool ok = std::isalnum(static_cast<unsigned char>(c)) || c == '_' ||
                    c == '.' || c == '/' || c == '-' || c == ' ' || c == '+';
    if (!ok) return false;
  }
  return !LooksLikeNumberOrWord(s);
}

std::string DoubleQuoted(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (u < 0x20 || u == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\x%02x", u);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string ScalarText(const ConfigNode& n) {
  switch (n.style) {
    case ConfigNode::Style::kPlain:
      return n.scalar;
    case ConfigNode::Style::kTagged:
      return n.tag + " " + DoubleQuoted(n.scalar);
    default:
      return SafePlain(n.scalar) ? n.scalar : DoubleQuoted(n.scalar);
  }
}

std::string KeyText(const std::string& key) {
  return SafePlain(key) && key.find(' ') == std::string::npos
             ? key
             : DoubleQuoted(key);
}

std::string Flow(const ConfigNode& n) {
  switch (n.kind) {
    case ConfigNode::Kind::kScalar:
      return ScalarText(n);
    case ConfigNode::Kind::kList: {
      std::string out = "[";
      for (std::size_t i = 0; i < n.items.size(); ++i)
        out += (i ? ", " : "") + Flow(n.items[i]);
      return out + "]";
    }
    case ConfigNode::Kind::kMap: {
      std::string out = "{";
      for (std::size_t i = 0; i < n.entries.size(); ++i)
        out += (i ? ", " : "") + KeyText(n.entries[i].key) + ": " +
               Flow(n.entries[i].value);
      return out + "}";
    }
    default:
      return "null";
  }
}

// Mappings nested in a value read better as blocks; lists of numbers and
// small mappings of scalars as one flow line.
bool PrefersFlow(const ConfigNode& n) {
  if (n.IsMap()) {
    for (const auto& e : n.entries)
      if (e.value.IsMap() || (e.value.IsList() && !e.value.items.empty() &&
                              e.value.items[0].IsMap()))
        return false;
    return true;
  }
  if (n.IsList()) {
    for (const ConfigNode& item : n.items)
      if (!item.IsScalar() && !(item.IsList() && PrefersFlow(item)))
        return false;
    return true;
  }
  return true;
}

void Block(const ConfigNode& n, std::size_t indent, std::string* out);

// `prefix` ("key:" or "-") followed by the value, inline or below.
void Value(const std::string& prefix, const ConfigNode& v, std::size_t indent,
           std::string* out) {
  const std::string pad(indent, ' ');
  if (v.IsScalar() || v.IsNull() || (v.IsMap() && v.entries.empty()) ||
      (v.IsList() && v.items.empty())) {
    *out += pad + prefix + " " + Flow(v) + "\n";
    return;
  }
  const std::string flow = Flow(v);
  if (PrefersFlow(v) &&
      indent + prefix.size() + 1 + flow.size() <= kLineWidth) {
    *out += pad + prefix + " " + flow + "\n";
    return;
  }
  if (v.IsMap()) {
    *out += pad + prefix + "\n";
    Block(v, indent + 2, out);
    return;
  }
  *out += pad + prefix + "\n";
  for (const ConfigNode& item : v.items) {
    const std::string item_flow = Flow(item);
    if (!item.IsMap() || item.entries.empty() ||
        indent + 4 + item_flow.size() <= kLineWidth) {
      *out += pad + "  - " + item_flow + "\n";
      continue;
    }
    // A long mapping item: its first key on the "- " line, the rest below.
    std::string body;
    Block(item, indent + 4, &body);
    body.replace(0, indent + 4, pad + "  - ");
    *out += body;
  }
}

void Block(const ConfigNode& n, std::size_t indent, std::string* out) {
  for (const ConfigNode::Entry& e : n.entries)
    Value(KeyText(e.key) + ":", e.value, indent, out);
}

}  // namespace

ConfigNode ParseYaml(const std::string& text, const std::string& file) {
  YAML::Node doc;
  try {
    // YAML::Load alone would silently drop every document after the first.
    if (const Documents docs = CountDocuments(text); docs.count > 1) {
      throw InputError(file, docs.second_line, "(yaml)",
                       "a scenario file holds one YAML document, found " +
                           std::to_string(docs.count) + " (separated by ---)");
    } else if (docs.count == 0) {
      return ConfigNode{};
    }
    doc = YAML::Load(text);
  } catch (const DocumentStarts::TooManyValues& e) {
    throw InputError(file, e.mark.line + 1, "(yaml)", TooManyValuesMessage());
  } catch (const DocumentStarts::OpenQuote& e) {
    throw InputError(file, e.mark.line + 1, "(yaml)", OpenQuoteMessage(e.mark));
  } catch (const YAML::DeepRecursion& e) {
    throw InputError(file, e.mark.line >= 0 ? e.mark.line + 1 : 0, "(yaml)",
                     TooDeepMessage(e.mark));
  } catch (const YAML::Exception& e) {
    throw YamlError(e, file, text);
  }
  return Converter(file, "").Convert(doc, "", 0);
}

ConfigNode ParseYamlValue(const std::string& text, const std::string& flag,
                          const std::string& key) {
  const std::string& named = key.empty() ? flag : key;
  // yaml-cpp reads bytes that are not UTF-8 as nothing at all (and quoting
  // them would put them in the error).
  if (!field_text::IsUtf8(text))
    throw InputError::Flag(named, "the value is not UTF-8 text");
  YAML::Node node;
  try {
    // YAML::Load would silently drop every document after the first.
    if (const Documents docs = CountDocuments(text); docs.count > 1) {
      throw InputError::Flag(
          named, "the value holds " + std::to_string(docs.count) +
                     " YAML documents (separated by ---), not one: '" + text +
                     "'");
    }
    node = YAML::Load(text);
  } catch (const DocumentStarts::TooManyValues&) {
    throw InputError::Flag(named, TooManyValuesMessage());
  } catch (const DocumentStarts::OpenQuote& e) {
    throw InputError::Flag(named, OpenQuoteMessage(e.mark));
  } catch (const YAML::DeepRecursion& e) {
    throw InputError::Flag(named, TooDeepMessage(e.mark));
  } catch (const YAML::Exception& e) {
    throw InputError::Flag(
        named, "invalid YAML value '" + text + "': " + YamlMessage(e, text));
  }
  // Keys inside the value are named under the path it sets.
  const std::string path =
      key.rfind(flag + " ", 0) == 0 ? key.substr(flag.size() + 1) : "";
  ConfigNode out = Converter("command line", flag).Convert(node, path, 0);
  out.SetOrigin(flag);
  return out;
}

std::string EmitYaml(const ConfigNode& node) {
  std::string out;
  if (node.IsMap()) {
    Block(node, 0, &out);
  } else {
    out = Flow(node) + "\n";
  }
  return out;
}

}  // namespace aia
