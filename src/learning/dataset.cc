#include "aia/learning/dataset.h"

#include <sqlite3.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "aia/core/error.h"

namespace aia {
namespace {

namespace fs = std::filesystem;

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
  neighbours BLOB, targets BLOB,
  PRIMARY KEY(episode, step, robot));
)";

// Little-endian float64 arrays (x86-64 and ARM64 are little-endian).
std::string Blob(const std::vector<double>& v) {
  std::string s(v.size() * sizeof(double), '\0');
  if (!v.empty()) std::memcpy(s.data(), v.data(), s.size());
  return s;
}

std::vector<double> Doubles(sqlite3_stmt* st, int col) {
  const int bytes = sqlite3_column_bytes(st, col);
  const void* p = sqlite3_column_blob(st, col);
  std::vector<double> v(bytes / sizeof(double));
  if (bytes % sizeof(double) != 0)
    throw std::runtime_error("blob of " + std::to_string(bytes) +
                             " bytes is not float64");
  if (!v.empty()) std::memcpy(v.data(), p, v.size() * sizeof(double));
  return v;
}

class Statement {
 public:
  Statement(sqlite3* db, const char* sql) : db_(db) {
    if (sqlite3_prepare_v2(db, sql, -1, &st_, nullptr) != SQLITE_OK)
      throw std::runtime_error(sqlite3_errmsg(db));
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
    throw std::runtime_error(sqlite3_errmsg(db_));
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
  char* err = nullptr;
  if (sqlite3_exec(db, sql, nullptr, nullptr, &err) != SQLITE_OK) {
    std::string what = err ? err : "unknown sqlite error";
    sqlite3_free(err);
    throw std::runtime_error(what);
  }
}

sqlite3* Open(const std::string& path, bool write) {
  sqlite3* db = nullptr;
  const int flags =
      write ? SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE : SQLITE_OPEN_READONLY;
  if (sqlite3_open_v2(path.c_str(), &db, flags, nullptr) != SQLITE_OK) {
    std::string what = db ? sqlite3_errmsg(db) : "cannot open";
    sqlite3_close(db);
    throw std::runtime_error(what);
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

void ReadFile(const std::string& file, Dataset* out) {
  sqlite3* db = Open(file, false);
  struct Closer {
    sqlite3* db;
    ~Closer() { sqlite3_close(db); }
  } closer{db};
  const std::string format = MetaValue(db, "format");
  if (format != "aia-igbnet-dataset")
    throw std::runtime_error("not an aia dataset (meta.format is '" + format +
                             "')");
  const std::string version = MetaValue(db, "version");
  if (version != std::to_string(kDatasetFormatVersion))
    throw std::runtime_error("dataset format version " + version +
                             ", this build reads " +
                             std::to_string(kDatasetFormatVersion));
  const std::size_t first_world = out->worlds.size();
  std::vector<std::int64_t> episodes;
  {
    Statement st(db,
                 "SELECT episode, seed, width, height, map_cell, lattice_step, "
                 "robot_radius, eps, robots, targets, steps, flowtime, "
                 "obstacles, log_det_prior FROM worlds ORDER BY episode");
    while (st.Step()) {
      sqlite3_stmt* s = st.get();
      DatasetWorld w;
      w.episode = sqlite3_column_int64(s, 0);
      w.seed = sqlite3_column_int64(s, 1);
      w.size = {sqlite3_column_double(s, 2), sqlite3_column_double(s, 3)};
      w.map_cell = sqlite3_column_double(s, 4);
      w.lattice_step = sqlite3_column_double(s, 5);
      w.robot_radius = sqlite3_column_double(s, 6);
      w.eps = sqlite3_column_double(s, 7);
      w.robots = sqlite3_column_int(s, 8);
      w.targets = sqlite3_column_int(s, 9);
      w.steps = sqlite3_column_int(s, 10);
      w.flowtime = sqlite3_column_int(s, 11);
      const std::vector<double> boxes = Doubles(s, 12);
      if (boxes.size() % 4 != 0)
        throw std::runtime_error("episode " + std::to_string(w.episode) +
                                 ": obstacles blob is not 4 floats per box");
      for (std::size_t i = 0; i < boxes.size(); i += 4)
        w.obstacles.push_back(
            {{boxes[i], boxes[i + 1]}, {boxes[i + 2], boxes[i + 3]}});
      w.log_det_prior = Doubles(s, 13);
      if (static_cast<int>(w.log_det_prior.size()) != w.targets ||
          w.robots <= 0 || !(w.size.x() > 0.0 && w.size.y() > 0.0) ||
          !(w.map_cell > 0.0) || !(w.eps > 0.0))
        throw std::runtime_error("episode " + std::to_string(w.episode) +
                                 ": world row is inconsistent");
      episodes.push_back(w.episode);
      out->worlds.push_back(std::move(w));
    }
  }
  Statement st(db,
               "SELECT episode, step, robot, x, y, label, useful, acted, "
               "neighbours, targets FROM samples ORDER BY episode, step, "
               "robot");
  while (st.Step()) {
    sqlite3_stmt* s = st.get();
    DatasetSample d;
    d.episode = sqlite3_column_int64(s, 0);
    d.step = sqlite3_column_int(s, 1);
    d.robot = sqlite3_column_int(s, 2);
    d.position = {sqlite3_column_double(s, 3), sqlite3_column_double(s, 4)};
    const int label = sqlite3_column_int(s, 5);
    const int acted = sqlite3_column_int(s, 7);
    d.useful = sqlite3_column_int(s, 6) != 0;
    const auto it =
        std::lower_bound(episodes.begin(), episodes.end(), d.episode);
    const std::string where = "episode " + std::to_string(d.episode) +
                              " step " + std::to_string(d.step) + " robot " +
                              std::to_string(d.robot);
    if (it == episodes.end() || *it != d.episode)
      throw std::runtime_error(where + ": sample of no world");
    d.world = static_cast<int>(first_world + (it - episodes.begin()));
    const DatasetWorld& w = out->worlds[d.world];
    if (label < 0 || label >= kNumMoves || acted < 0 || acted > kNumMoves ||
        d.robot < 0 || d.robot >= w.robots)
      throw std::runtime_error(where + ": label or robot out of range");
    d.label = static_cast<Move>(label);
    d.acted = static_cast<Move>(acted);
    const std::vector<double> nb = Doubles(s, 8);
    const std::vector<double> tg = Doubles(s, 9);
    if (nb.size() % 2 != 0 || tg.size() != 6u * w.targets)
      throw std::runtime_error(where + ": neighbours or targets blob size");
    for (std::size_t i = 0; i < nb.size(); i += 2)
      d.neighbours.emplace_back(nb[i], nb[i + 1]);
    d.targets.resize(w.targets);
    for (int k = 0; k < w.targets; ++k) {
      const double* t = tg.data() + 6 * k;
      HeatSource& h = d.targets[k];
      h.mean = {t[0], t[1]};
      h.cov << t[2], t[3], t[3], t[4];
      h.log_det = t[5];
    }
    out->samples.push_back(std::move(d));
  }
}

}  // namespace

struct DatasetWriter::Db {
  sqlite3* db = nullptr;
  ~Db() { sqlite3_close(db); }
};

DatasetWriter::DatasetWriter(const std::string& path, const std::string& recipe,
                             const std::string& key)
    : db_(std::make_unique<Db>()) {
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
  } catch (const std::runtime_error& e) {
    if (dynamic_cast<const InputError*>(&e)) throw;
    throw InputError(path, 0, key, std::string("cannot open: ") + e.what());
  }
}

DatasetWriter::~DatasetWriter() = default;

void DatasetWriter::WriteEpisode(const DatasetWorld& w,
                                 const std::vector<DatasetSample>& samples) {
  sqlite3* db = db_->db;
  Exec(db, "BEGIN IMMEDIATE");
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
                 "INSERT INTO samples VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    std::vector<double> nb, tg;
    for (const DatasetSample& d : samples) {
      nb.clear();
      tg.clear();
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
      st.Run();
    }
    Exec(db, "COMMIT");
  } catch (...) {
    sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
  done_.insert(w.episode);
}

Dataset ReadDataset(const std::vector<std::string>& paths,
                    const std::string& key) {
  Dataset out;
  if (paths.empty()) throw InputError("command line", 0, key, "is required");
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
    } else if (fs::is_regular_file(p, ec)) {
      files.push_back(p);
    } else {
      throw InputError(p, 0, key, "no such file or folder");
    }
    for (const std::string& f : files) {
      try {
        ReadFile(f, &out);
      } catch (const InputError&) {
        throw;
      } catch (const std::exception& e) {
        throw InputError(f, 0, key, e.what());
      }
    }
  }
  return out;
}

}  // namespace aia
