#include "aia/learning/dataset.h"

#include <sqlite3.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <new>
#include <stdexcept>

#include "aia/core/error.h"
#include "aia/core/fields.h"
#include "aia/core/io.h"
#include "aia/scenario/config.h"
#include "aia/world/lattice.h"

namespace aia {
namespace {

namespace fs = std::filesystem;

bool AllFinite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(),
                     [](double x) { return std::isfinite(x); });
}

// Within the workspace, or a lattice step off its edge at most (a robot
// pushed against a wall); finite.
bool Inside(const DatasetWorld& w, const Vec2& p) {
  const double m = w.lattice_step;
  return p.allFinite() && p.x() >= -m && p.y() >= -m &&
         p.x() <= w.size.x() + m && p.y() <= w.size.y() + m;
}

// What is wrong with a world row, against the scenario's own ranges
// (docs/scenarios.md), so that a damaged or edited file is refused before
// a map, lattice or image is made from it; empty when nothing is.
std::string WorldRowProblem(const DatasetWorld& w) {
  const auto in = [](double x, double lo, double hi) {
    return std::isfinite(x) && x >= lo && x <= hi;
  };
  if (!in(w.size.x(), 0.1, 1e4) || !in(w.size.y(), 0.1, 1e4))
    return "width and height must be in [0.1, 10000]";
  if (!in(w.map_cell, 0.001, 1e4) ||
      (w.size.x() / w.map_cell) * (w.size.y() / w.map_cell) >
          limits::kMaxGridCells)
    return "map_cell must be in [0.001, 10000], at most 5e7 cells";
  if (!in(w.lattice_step, 0.001, 1e4) ||
      (w.size.x() / w.lattice_step) * (w.size.y() / w.lattice_step) >
          limits::kMaxLatticePoints)
    return "lattice_step must be in [0.001, 10000], at most 1e6 points";
  if (!in(w.robot_radius, 0.001, 1e4) || w.robot_radius >= w.lattice_step / 2)
    return "robot_radius must be in [0.001, 10000] and below lattice_step / 2";
  if (!(std::isfinite(w.eps) && w.eps > 0.0)) return "eps must be above 0";
  if (w.robots <= 0 || w.targets < 0 || w.steps < 0)
    return "robots must be above 0, targets and steps not negative";
  if (static_cast<int>(w.log_det_prior.size()) != w.targets ||
      !AllFinite(w.log_det_prior))
    return "log_det_prior must hold one finite value per target";
  for (const Box& b : w.obstacles)
    if (!b.lo.allFinite() || !b.hi.allFinite() || !(b.lo.x() <= b.hi.x()) ||
        !(b.lo.y() <= b.hi.y()))
      return "an obstacle box is not finite or not ordered";
  return "";
}

constexpr const char* kSchema = R"(
CREATE TABLE IF NOT EXISTS meta(key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS worlds(
  episode INTEGER PRIMARY KEY, seed INTEGER NOT NULL,
  width REAL NOT NULL, height REAL NOT NULL, map_cell REAL NOT NULL,
  lattice_step REAL NOT NULL, robot_radius REAL NOT NULL, eps REAL NOT NULL,
  robots INTEGER NOT NULL, targets INTEGER NOT NULL, steps INTEGER NOT NULL,
  flowtime INTEGER NOT NULL, obstacles BLOB, log_det_prior BLOB);
CREATE TABLE IF NOT EXISTS samples(
  episode INTEGER NOT NULL, step INTEGER NOT NULL, robot INTEGER NOT NULL,
  x REAL NOT NULL, y REAL NOT NULL, label INTEGER NOT NULL,
  useful INTEGER NOT NULL, acted INTEGER NOT NULL,
  neighbours BLOB, targets BLOB, search BLOB, came INTEGER NOT NULL,
  PRIMARY KEY(episode, step, robot));
)";

// Little-endian float64 arrays (x86-64 and ARM64 are little-endian).
std::string Blob(const std::vector<double>& v) {
  std::string s(v.size() * sizeof(double), '\0');
  if (!v.empty()) std::memcpy(s.data(), v.data(), s.size());
  return s;
}

// A column of the wrong type or range (its row's context is added by the
// row's reader).
struct ColumnError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// What a column holds, for an error: SQLite converts between types at will
// (a label 'x' read as 0, 1.7 as 1), so each column's type is checked.
std::string ColumnProblem(sqlite3_stmt* st, int col, const char* want) {
  static const char* const kTypes[] = {"",     "an integer", "a real number",
                                       "text", "a blob",     "null"};
  const int type = sqlite3_column_type(st, col);
  return std::string("column ") + sqlite3_column_name(st, col) + " holds " +
         (type >= 1 && type <= 5 ? kTypes[type] : "an unknown type") +
         ", not " + want;
}

std::int64_t Integer(sqlite3_stmt* st, int col) {
  if (sqlite3_column_type(st, col) != SQLITE_INTEGER)
    throw ColumnError(ColumnProblem(st, col, "an integer"));
  return sqlite3_column_int64(st, col);
}

// An integer column that fits an int (a count, an index, a move).
int SmallInteger(sqlite3_stmt* st, int col) {
  const std::int64_t v = Integer(st, col);
  if (v < std::numeric_limits<int>::min() ||
      v > std::numeric_limits<int>::max())
    throw ColumnError(std::string("column ") + sqlite3_column_name(st, col) +
                      " holds " + std::to_string(v) + ", out of range");
  return static_cast<int>(v);
}

double Real(sqlite3_stmt* st, int col) {
  const int type = sqlite3_column_type(st, col);
  if (type != SQLITE_FLOAT && type != SQLITE_INTEGER)
    throw ColumnError(ColumnProblem(st, col, "a number"));
  return sqlite3_column_double(st, col);
}

std::vector<double> Doubles(sqlite3_stmt* st, int col) {
  const int type = sqlite3_column_type(st, col);
  if (type != SQLITE_BLOB && type != SQLITE_NULL)
    throw ColumnError(ColumnProblem(st, col, "a blob of float64"));
  const int bytes = sqlite3_column_bytes(st, col);
  const void* p = sqlite3_column_blob(st, col);
  std::vector<double> v(bytes / sizeof(double));
  if (bytes % sizeof(double) != 0)
    throw std::runtime_error("blob of " + std::to_string(bytes) +
                             " bytes is not float64");
  if (!v.empty()) std::memcpy(v.data(), p, v.size() * sizeof(double));
  return v;
}

// A failed SQLite call, with its result code and the errno of the system
// call that failed under it (0 when none did).
class SqliteError : public std::runtime_error {
 public:
  SqliteError(sqlite3* db, int code)
      : std::runtime_error(db ? sqlite3_errmsg(db) : sqlite3_errstr(code)),
        code_(code),
        errno_(db ? sqlite3_system_errno(db) : 0) {}
  int code() const { return code_ & 0xff; }  // the primary result code
  int system_errno() const { return errno_; }

 private:
  int code_, errno_;
};

// A write to `path` that the file system refused (a full disk, an I/O
// error) as aia's I/O error, "cannot write 'PATH': <errno text>"; other
// SQLite errors are passed on as they are.
[[noreturn]] void ThrowWriteError(const SqliteError& e,
                                  const std::string& path) {
  const int code = e.code();
  if (code != SQLITE_FULL && code != SQLITE_IOERR && code != SQLITE_CANTOPEN &&
      code != SQLITE_READONLY)
    throw e;
  std::string why;
  if (code == SQLITE_FULL) {
    why = std::strerror(ENOSPC);  // SQLite's own "database or disk is full"
  } else if (e.system_errno() != 0) {
    why = std::strerror(e.system_errno());
  } else {
    why = sqlite3_errstr(code);
  }
  ThrowCannotWrite(path, why);
}

class Statement {
 public:
  Statement(sqlite3* db, const char* sql) : db_(db) {
    const int rc = sqlite3_prepare_v2(db, sql, -1, &st_, nullptr);
    if (rc != SQLITE_OK) throw SqliteError(db, rc);
  }
  ~Statement() { sqlite3_finalize(st_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  sqlite3_stmt* get() { return st_; }
  void Bind(int i, std::int64_t v) { sqlite3_bind_int64(st_, i, v); }
  void Bind(int i, double v) { sqlite3_bind_double(st_, i, v); }
  void Bind(int i, const std::string& v) {
    sqlite3_bind_blob(st_, i, v.data(), static_cast<int>(v.size()),
                      SQLITE_TRANSIENT);
  }
  void BindText(int i, const std::string& v) {
    sqlite3_bind_text(st_, i, v.data(), static_cast<int>(v.size()),
                      SQLITE_TRANSIENT);
  }
  // Steps once; true while rows come.
  bool Step() {
    const int rc = sqlite3_step(st_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw SqliteError(db_, rc);
  }
  void Run() {
    Step();
    sqlite3_reset(st_);
    sqlite3_clear_bindings(st_);
  }

 private:
  sqlite3* db_;
  sqlite3_stmt* st_ = nullptr;
};

void Exec(sqlite3* db, const char* sql) {
  const int rc = sqlite3_exec(db, sql, nullptr, nullptr, nullptr);
  if (rc != SQLITE_OK) throw SqliteError(db, rc);
}

sqlite3* Open(const std::string& path, bool write) {
  sqlite3* db = nullptr;
  const int flags =
      write ? SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE : SQLITE_OPEN_READONLY;
  if (const int rc = sqlite3_open_v2(path.c_str(), &db, flags, nullptr);
      rc != SQLITE_OK) {
    const SqliteError e(db, rc);
    sqlite3_close(db);
    throw e;
  }
  sqlite3_busy_timeout(db, 5000);
  return db;
}

std::string MetaValue(sqlite3* db, const std::string& key) {
  Statement st(db, "SELECT value FROM meta WHERE key = ?");
  st.BindText(1, key);
  if (!st.Step()) return "";
  const unsigned char* t = sqlite3_column_text(st.get(), 0);
  return t ? reinterpret_cast<const char*>(t) : "";
}

// What a file's format version holds: search points from version 2 on, the
// move a robot came by from version 3 on.
struct FileFormat {
  bool has_search = false;
  bool has_came = false;
};

// meta.format and meta.version, checked.
FileFormat ReadFormat(sqlite3* db) {
  const std::string format = MetaValue(db, "format");
  if (format != "aia-igbnet-dataset")
    throw std::runtime_error("not an aia dataset (meta.format is '" + format +
                             "')");
  const std::string version = MetaValue(db, "version");
  if (version != "1" && version != "2" &&
      version != std::to_string(kDatasetFormatVersion))
    throw std::runtime_error("dataset format version " + version +
                             ", this build reads 1 to " +
                             std::to_string(kDatasetFormatVersion));
  FileFormat f;
  f.has_search = version != "1";
  f.has_came = version != "1" && version != "2";
  return f;
}

// One row of the worlds table, checked (WorldRowProblem).
DatasetWorld ReadWorldRow(sqlite3_stmt* s) {
  DatasetWorld w;
  w.episode = Integer(s, 0);
  std::vector<double> boxes;
  try {
    w.seed = Integer(s, 1);
    w.size = {Real(s, 2), Real(s, 3)};
    w.map_cell = Real(s, 4);
    w.lattice_step = Real(s, 5);
    w.robot_radius = Real(s, 6);
    w.eps = Real(s, 7);
    w.robots = SmallInteger(s, 8);
    w.targets = SmallInteger(s, 9);
    w.steps = SmallInteger(s, 10);
    w.flowtime = SmallInteger(s, 11);
    boxes = Doubles(s, 12);
    w.log_det_prior = Doubles(s, 13);
  } catch (const ColumnError& e) {
    throw std::runtime_error("episode " + std::to_string(w.episode) + ": " +
                             e.what());
  }
  if (boxes.size() % 4 != 0)
    throw std::runtime_error("episode " + std::to_string(w.episode) +
                             ": obstacles blob is not 4 floats per box");
  // As many as a world can have (a million zero-size boxes were read).
  if (boxes.size() / 4 > static_cast<std::size_t>(limits::kMaxBodies))
    throw std::runtime_error("episode " + std::to_string(w.episode) + ": " +
                             std::to_string(boxes.size() / 4) +
                             " obstacle boxes, more than a " + "world has (" +
                             std::to_string(limits::kMaxBodies) + ")");
  for (std::size_t i = 0; i < boxes.size(); i += 4)
    w.obstacles.push_back(
        {{boxes[i], boxes[i + 1]}, {boxes[i + 2], boxes[i + 3]}});
  if (const std::string problem = WorldRowProblem(w); !problem.empty())
    throw std::runtime_error("episode " + std::to_string(w.episode) +
                             ": world row is inconsistent: " + problem);
  return w;
}

// Appends the file's worlds, in episode order; returns their episodes.
std::vector<std::int64_t> ReadWorlds(sqlite3* db, Dataset* out) {
  std::vector<std::int64_t> episodes;
  Statement st(db,
               "SELECT episode, seed, width, height, map_cell, lattice_step, "
               "robot_radius, eps, robots, targets, steps, flowtime, "
               "obstacles, log_det_prior FROM worlds ORDER BY episode");
  while (st.Step()) {
    DatasetWorld w = ReadWorldRow(st.get());
    episodes.push_back(w.episode);
    out->worlds.push_back(std::move(w));
  }
  return episodes;
}

// The samples query of a file of format `f`.
const char* SamplesQuery(const FileFormat& f) {
  return f.has_came     ? "SELECT episode, step, robot, x, y, label, "
                          "useful, acted, neighbours, targets, search, "
                          "came FROM samples ORDER BY episode, step, robot"
         : f.has_search ? "SELECT episode, step, robot, x, y, label, useful, "
                          "acted, neighbours, targets, search FROM samples "
                          "ORDER BY episode, step, robot"
                        : "SELECT episode, step, robot, x, y, label, useful, "
                          "acted, neighbours, targets FROM samples ORDER BY "
                          "episode, step, robot";
}

// The targets blob (6 floats per target: mean, covariance xx, xy, yy, log
// det) into d->targets; each covariance checked. `where` names the sample.
void ReadBeliefs(const std::vector<double>& tg, const DatasetWorld& w,
                 const std::string& where, DatasetSample* d) {
  d->targets.resize(w.targets);
  for (int k = 0; k < w.targets; ++k) {
    const double* t = tg.data() + 6 * k;
    HeatSource& h = d->targets[k];
    h.mean = {t[0], t[1]};
    h.cov << t[2], t[3], t[3], t[4];
    h.log_det = t[5];
    // A covariance (positive semidefinite): the heat stamp's window and
    // weight read its square roots.
    if (!(t[2] >= 0.0 && t[4] >= 0.0 && t[2] * t[4] - t[3] * t[3] >= 0.0))
      throw std::runtime_error(where + ": target " + std::to_string(k) +
                               "'s belief covariance is not one (" +
                               FormatNumber(t[2]) + ", " + FormatNumber(t[3]) +
                               ", " + FormatNumber(t[4]) + ")");
  }
}

// The search blob, (target, count, count x (x, y)) per target with search
// points, into d->search.
void ReadSearchPoints(const std::vector<double>& sp, const DatasetWorld& w,
                      const std::string& where, DatasetSample* d) {
  for (std::size_t i = 0; i < sp.size();) {
    if (i + 2 > sp.size())
      throw std::runtime_error(where + ": search blob size");
    const double k = sp[i], count = sp[i + 1];
    if (!(k >= 0 && k < w.targets && k == std::floor(k)) ||
        !(count >= 1 && count == std::floor(count) &&
          i + 2 + 2 * count <= sp.size()))
      throw std::runtime_error(where + ": search blob is inconsistent");
    if (d->search.empty()) d->search.resize(w.targets);
    std::vector<Vec2>& points = d->search[static_cast<int>(k)];
    for (int a = 0; a < static_cast<int>(count); ++a) {
      points.emplace_back(sp[i + 2 + 2 * a], sp[i + 3 + 2 * a]);
      if (!points.back().allFinite())
        throw std::runtime_error(where + ": search point not finite");
    }
    i += 2 + 2 * static_cast<std::size_t>(count);
  }
}

// One row of the samples table, checked against its world (one of `worlds`,
// whose first `first_world` came from other files; `episodes`: this file's).
DatasetSample ReadSampleRow(sqlite3_stmt* s, const FileFormat& f,
                            const std::vector<std::int64_t>& episodes,
                            std::size_t first_world,
                            const std::vector<DatasetWorld>& worlds) {
  DatasetSample d;
  d.episode = Integer(s, 0);
  d.step = SmallInteger(s, 1);
  d.robot = SmallInteger(s, 2);
  const std::string where = "episode " + std::to_string(d.episode) + " step " +
                            std::to_string(d.step) + " robot " +
                            std::to_string(d.robot);
  try {
    d.position = {Real(s, 3), Real(s, 4)};
    const int label = SmallInteger(s, 5);
    const int useful = SmallInteger(s, 6);
    const int acted = SmallInteger(s, 7);
    const auto it =
        std::lower_bound(episodes.begin(), episodes.end(), d.episode);
    if (it == episodes.end() || *it != d.episode)
      throw std::runtime_error(where + ": sample of no world");
    d.world = static_cast<int>(first_world + (it - episodes.begin()));
    const DatasetWorld& w = worlds[d.world];
    if (label < 0 || label >= kNumMoves || acted < 0 || acted > kNumMoves ||
        d.robot < 0 || d.robot >= w.robots || d.step < 0 || useful < 0 ||
        useful > 1)
      throw std::runtime_error(where +
                               ": label, acted, useful, step or robot out of "
                               "range");
    d.useful = useful != 0;
    d.label = static_cast<Move>(label);
    d.acted = static_cast<Move>(acted);
    const std::vector<double> nb = Doubles(s, 8);
    const std::vector<double> tg = Doubles(s, 9);
    // At most the team (a 100 MB blob was read).
    if (nb.size() % 2 != 0 ||
        nb.size() / 2 > static_cast<std::size_t>(w.robots) ||
        tg.size() != 6u * w.targets)
      throw std::runtime_error(where + ": neighbours or targets blob size");
    if (!Inside(w, d.position) || !AllFinite(nb) || !AllFinite(tg))
      throw std::runtime_error(where +
                               ": position outside the workspace, or a "
                               "neighbour or belief not finite");
    for (std::size_t i = 0; i < nb.size(); i += 2)
      d.neighbours.emplace_back(nb[i], nb[i + 1]);
    ReadBeliefs(tg, w, where, &d);
    if (f.has_search) ReadSearchPoints(Doubles(s, 10), w, where, &d);
    if (f.has_came) {
      const int came = SmallInteger(s, 11);
      if (came < 0 || came > kNumMoves)
        throw std::runtime_error(where + ": came out of range");
      d.came = static_cast<Move>(came);
    }
    return d;
  } catch (const ColumnError& e) {
    throw std::runtime_error(where + ": " + e.what());
  }
}

// Appends the file's worlds and samples; returns its recipe.
std::string ReadFile(const std::string& file, Dataset* out) {
  sqlite3* db = Open(file, false);
  struct Closer {
    sqlite3* db;
    ~Closer() { sqlite3_close(db); }
  } closer{db};
  const FileFormat format = ReadFormat(db);
  const std::size_t first_world = out->worlds.size();
  const std::vector<std::int64_t> episodes = ReadWorlds(db, out);
  Statement st(db, SamplesQuery(format));
  while (st.Step())
    out->samples.push_back(
        ReadSampleRow(st.get(), format, episodes, first_world, out->worlds));
  return MetaValue(db, "recipe");
}

}  // namespace

RobotMemory SampleMemory(const DatasetSample& s, const DatasetWorld& w) {
  RobotMemory m;
  if (!s.search.empty()) m.search = &s.search;
  if (s.came != Move::kStay) {
    const auto d = MoveDelta(s.came);
    m.moved = true;
    m.came_from = s.position - w.lattice_step * Vec2(d[0], d[1]);
  }
  return m;
}

struct DatasetWriter::Db {
  sqlite3* db = nullptr;
  ~Db() { sqlite3_close(db); }
};

DatasetWriter::DatasetWriter(const std::string& path, const std::string& recipe,
                             const std::string& key)
    : db_(std::make_unique<Db>()), path_(path) {
  try {
    db_->db = Open(path, true);
    Exec(db_->db, "PRAGMA synchronous = FULL");
    Exec(db_->db, kSchema);
    const std::string format = MetaValue(db_->db, "format");
    if (format.empty()) {
      Exec(db_->db, "BEGIN");
      Statement st(db_->db, "INSERT INTO meta(key, value) VALUES (?, ?)");
      const std::pair<std::string, std::string> rows[] = {
          {"format", "aia-igbnet-dataset"},
          {"version", std::to_string(kDatasetFormatVersion)},
          {"recipe", recipe}};
      for (const auto& [k, v] : rows) {
        st.BindText(1, k);
        st.BindText(2, v);
        st.Run();
      }
      Exec(db_->db, "COMMIT");
    } else if (format != "aia-igbnet-dataset" ||
               MetaValue(db_->db, "version") !=
                   std::to_string(kDatasetFormatVersion)) {
      throw InputError(path, 0, key, "is not an aia dataset of this version");
    } else if (MetaValue(db_->db, "recipe") != recipe) {
      throw InputError(
          path, 0, key,
          "was written with another recipe; resume with the same options or "
          "choose another folder (written: " +
              MetaValue(db_->db, "recipe") + ")");
    }
    Statement st(db_->db, "SELECT episode FROM worlds");
    while (st.Step()) done_.insert(sqlite3_column_int64(st.get(), 0));
    // An episode's world and samples are written in one transaction: samples
    // without their world were left by a change made outside aia, and would
    // collide with the episode's samples when it runs again.
    Statement orphans(db_->db,
                      "SELECT COUNT(DISTINCT episode) FROM samples WHERE "
                      "episode NOT IN (SELECT episode FROM worlds)");
    const std::int64_t lost =
        orphans.Step() ? sqlite3_column_int64(orphans.get(), 0) : 0;
    if (lost > 0)
      throw InputError(
          path, 0, key,
          "holds samples of " +
              (lost == 1 ? std::string("an episode without its world record")
                         : std::to_string(lost) +
                               " episodes without their world records") +
              " (the shard was changed outside aia): remove the shard to "
              "write it again, or choose another folder");
  } catch (const SqliteError& e) {
    // A full disk or an I/O error is exit 1 with the path; a file that is
    // not a database is bad input.
    if (e.code() == SQLITE_FULL || e.code() == SQLITE_IOERR)
      ThrowWriteError(e, path);
    throw InputError(path, 0, key, std::string("cannot open: ") + e.what());
  } catch (const InputError&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw InputError(path, 0, key, std::string("cannot open: ") + e.what());
  }
}

DatasetWriter::~DatasetWriter() = default;

void DatasetWriter::WriteEpisode(const DatasetWorld& w,
                                 const std::vector<DatasetSample>& samples) {
  sqlite3* db = db_->db;
  try {
    Exec(db, "BEGIN IMMEDIATE");
  } catch (const SqliteError& e) {
    ThrowWriteError(e, path_);
  }
  try {
    {
      Statement st(db,
                   "INSERT INTO worlds VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, "
                   "?, ?, ?, ?)");
      std::vector<double> boxes;
      for (const Box& b : w.obstacles)
        boxes.insert(boxes.end(), {b.lo.x(), b.lo.y(), b.hi.x(), b.hi.y()});
      st.Bind(1, w.episode);
      st.Bind(2, w.seed);
      st.Bind(3, w.size.x());
      st.Bind(4, w.size.y());
      st.Bind(5, w.map_cell);
      st.Bind(6, w.lattice_step);
      st.Bind(7, w.robot_radius);
      st.Bind(8, w.eps);
      st.Bind(9, static_cast<std::int64_t>(w.robots));
      st.Bind(10, static_cast<std::int64_t>(w.targets));
      st.Bind(11, static_cast<std::int64_t>(w.steps));
      st.Bind(12, static_cast<std::int64_t>(w.flowtime));
      st.Bind(13, Blob(boxes));
      st.Bind(14, Blob(w.log_det_prior));
      st.Run();
    }
    Statement st(db,
                 "INSERT INTO samples VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, "
                 "?, ?)");
    std::vector<double> nb, tg, sp;
    for (const DatasetSample& d : samples) {
      nb.clear();
      tg.clear();
      sp.clear();
      for (std::size_t k = 0; k < d.search.size(); ++k) {
        if (d.search[k].empty()) continue;
        sp.insert(sp.end(), {static_cast<double>(k),
                             static_cast<double>(d.search[k].size())});
        for (const Vec2& p : d.search[k]) sp.insert(sp.end(), {p.x(), p.y()});
      }
      for (const Vec2& p : d.neighbours) nb.insert(nb.end(), {p.x(), p.y()});
      for (const HeatSource& h : d.targets)
        tg.insert(tg.end(), {h.mean.x(), h.mean.y(), h.cov(0, 0), h.cov(0, 1),
                             h.cov(1, 1), h.log_det});
      st.Bind(1, d.episode);
      st.Bind(2, static_cast<std::int64_t>(d.step));
      st.Bind(3, static_cast<std::int64_t>(d.robot));
      st.Bind(4, d.position.x());
      st.Bind(5, d.position.y());
      st.Bind(6, static_cast<std::int64_t>(d.label));
      st.Bind(7, static_cast<std::int64_t>(d.useful ? 1 : 0));
      st.Bind(8, static_cast<std::int64_t>(d.acted));
      st.Bind(9, Blob(nb));
      st.Bind(10, Blob(tg));
      st.Bind(11, Blob(sp));
      st.Bind(12, static_cast<std::int64_t>(d.came));
      st.Run();
    }
    Exec(db, "COMMIT");
  } catch (const SqliteError& e) {
    sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
    ThrowWriteError(e, path_);
  } catch (...) {
    sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
  done_.insert(w.episode);
}

int ShardCount(const std::string& path) {
  const fs::path file(path);
  const std::string name = file.filename().string();
  const std::size_t of = name.find("-of-");
  if (name.rfind("shard-", 0) != 0 || of == std::string::npos ||
      name.size() < of + 4 + 7 ||
      name.compare(name.size() - 7, 7, ".sqlite") != 0)
    return 0;
  const std::string n = name.substr(of + 4, name.size() - of - 4 - 7);
  if (n.empty() || n.size() > 6 ||
      n.find_first_not_of("0123456789") != std::string::npos)
    return 0;
  return std::stoi(n);
}

namespace {

// What is wrong with a shard SQLite could not read: left mid-episode by a
// stopped aia dataset (its rollback journal beside it, which only a writer
// can roll back), or not a shard at all.
std::string UnreadableShard(const std::string& path, const SqliteError& e) {
  std::error_code ec;
  if (std::filesystem::exists(path + "-journal", ec))
    return "holds an unfinished episode (" + path +
           "-journal): an aia dataset that was stopped left it (run that "
           "command again, which drops the episode and goes on), or one is "
           "writing it now (read the shard once it has finished) (SQLite: " +
           e.what() + ")";
  return std::string("not an aia dataset shard (SQLite: ") + e.what() + ")";
}

}  // namespace

std::string DatasetRecipe(const std::string& path, const std::string& key) {
  sqlite3* db = nullptr;
  try {
    db = Open(path, false);
    std::string recipe = MetaValue(db, "recipe");
    sqlite3_close(db);
    return recipe;
  } catch (const SqliteError& e) {
    sqlite3_close(db);
    throw InputError(path, 0, key, UnreadableShard(path, e));
  }
}

namespace {

// The recipe without its shard count: shards of one recipe with different
// counts hold the same episodes.
std::string RecipeWithoutShards(std::string recipe) {
  const std::size_t at = recipe.find(" shards=");
  if (at == std::string::npos) return recipe;
  std::size_t end = at + 8;
  while (end < recipe.size() && recipe[end] != ' ') ++end;
  return recipe.erase(at, end - at);
}

}  // namespace

std::vector<std::string> DatasetFiles(const std::vector<std::string>& paths,
                                      const std::string& key) {
  if (paths.empty()) throw InputError::Flag(key, "is required");
  std::vector<std::string> out;
  std::vector<std::string> given;  // the path that named each file
  for (const std::string& p : paths) {
    std::vector<std::string> files;
    std::error_code ec;
    if (fs::is_directory(p, ec)) {
      for (const auto& entry : fs::directory_iterator(p, ec))
        if (entry.path().extension() == ".sqlite")
          files.push_back(entry.path().string());
      std::sort(files.begin(), files.end());
      if (files.empty())
        throw InputError(p, 0, key, "holds no dataset (*.sqlite) files");
      // One shard set per folder: sets written with other --shard counts
      // split the same episodes differently, and would be read together.
      std::string first;
      int first_n = 0;
      for (const std::string& f : files) {
        const int n = ShardCount(f);
        if (n == 0) continue;
        if (first_n == 0) {
          first = f;
          first_n = n;
        } else if (n != first_n) {
          throw InputError(
              p, 0, key,
              "mixes shard sets: '" + first + "' is one of " +
                  std::to_string(first_n) + " shards, '" + f + "' one of " +
                  std::to_string(n) +
                  " (written with another --shard K/N); keep one set per "
                  "folder");
        }
      }
      // The shards of a set share one recipe: another was written with
      // other options (a resubmitted task with changed flags).
      std::string recipe;
      for (const std::string& f : files) {
        if (ShardCount(f) == 0) continue;
        const std::string r = DatasetRecipe(f, key);
        if (r.empty()) continue;
        if (recipe.empty()) {
          recipe = r;
          first = f;
        } else if (r != recipe) {
          throw InputError(p, 0, key,
                           "mixes shards written with other options: '" +
                               first + "' (" + recipe + ") and '" + f + "' (" +
                               r + "); keep one recipe per folder");
        }
      }
    } else if (fs::is_regular_file(p, ec)) {
      files.push_back(p);
    } else if (const std::string kind = NonRegularKind(p); !kind.empty()) {
      throw InputError(p, 0, key, "is " + kind + ", not a dataset file");
    } else {
      throw InputError(p, 0, key, "no such file or folder");
    }
    // A file named twice (the same path, a link, or a file and its folder)
    // would count every sample twice.
    for (const std::string& f : files) {
      for (std::size_t i = 0; i < out.size(); ++i)
        if (SameFile(f, out[i]))
          throw InputError::Flag(
              key,
              "'" + f + "' is read twice (as '" + given[i] + "' and as '" + p +
                  "'): its samples would count twice; give each dataset once");
      out.push_back(f);
      given.push_back(p);
    }
  }
  return out;
}

Dataset ReadDataset(const std::vector<std::string>& paths,
                    const std::string& key) {
  Dataset out;
  // (recipe without shard count, episode) -> file: the same episode from two
  // files (a copied shard, shard sets of two counts) is refused.
  std::map<std::pair<std::string, std::int64_t>, std::string> seen;
  for (const std::string& f : DatasetFiles(paths, key)) {
    // aia dataset holds an flock on the shard it writes: read now, a shard
    // would give the episodes written so far (and a resume later others).
    if (LockedByAnotherProcess(f))
      throw InputError(f, 0, key,
                       "is being written by aia dataset (it holds the "
                       "shard's lock): read it once that has finished");
    const std::size_t first_world = out.worlds.size();
    std::string recipe;
    try {
      recipe = RecipeWithoutShards(ReadFile(f, &out));
    } catch (const InputError&) {
      throw;
    } catch (const SqliteError& e) {
      throw InputError(f, 0, key, UnreadableShard(f, e));
    } catch (const std::bad_alloc&) {
      throw;  // out of memory is not bad input (cli.cc says it)
    } catch (const std::exception& e) {
      throw InputError(f, 0, key, e.what());
    }
    for (std::size_t w = first_world; w < out.worlds.size(); ++w) {
      const auto [it, fresh] =
          seen.emplace(std::make_pair(recipe, out.worlds[w].episode), f);
      if (!fresh)
        throw InputError(f, 0, key,
                         "episode " + std::to_string(out.worlds[w].episode) +
                             " is also in '" + it->second +
                             "' (the same recipe): its samples would count "
                             "twice; read one copy");
    }
  }
  return out;
}

std::vector<std::vector<int>> SamplesByWorld(const Dataset& d) {
  std::vector<std::vector<int>> out(d.worlds.size());
  for (int i = 0; i < static_cast<int>(d.samples.size()); ++i)
    out[d.samples[i].world].push_back(i);
  return out;
}

std::uint8_t ValidMoveBits(const Lattice& lattice, const Vec2& position) {
  const int here = lattice.NearestPoint(position);
  std::uint8_t bits = 0;
  for (int m = 0; m < kNumMoves; ++m)
    if (lattice.Valid(here, static_cast<Move>(m))) bits |= 1u << m;
  return bits;
}

}  // namespace aia
