// aia._aia: the C++ core of the Python package (python/aia/__init__.py
// wraps it; docs/python.md). A Mission is one episode of the same loop as
// `aia run` (runtime/episode.h) whose moves come from Python; a builtin
// policy is a registered policy deciding on a mission's state with the
// same truth fence as in the loop. Each area is bound by its own Bind*
// function at the end of the file.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "aia/commands/episode_picture.h"
#include "aia/commands/eval.h"
#include "aia/core/error.h"
#include "aia/core/field_io.h"
#include "aia/core/field_values.h"
#include "aia/core/interrupt.h"
#include "aia/core/plugin.h"
#include "aia/core/rng.h"
#include "aia/core/thread_pool.h"
#include "aia/estimation/heatmap.h"
#include "aia/learning/channels.h"
#include "aia/learning/dataset.h"
#include "aia/learning/igbnet_policy.h"
#include "aia/learning/scorer.h"
#include "aia/planning/policy.h"
#include "aia/planning/registry.h"
#include "aia/render/scene.h"
#include "aia/runtime/episode.h"
#include "aia/runtime/generated.h"
#include "aia/runtime/instance.h"
#include "aia/runtime/mission.h"
#include "aia/runtime/observers.h"
#include "aia/runtime/policies.h"
#include "aia/runtime/policy_states.h"
#include "aia/scenario/loader.h"
#include "aia/scenario/yaml.h"

namespace py = pybind11;

namespace aia {
namespace python {
namespace {

// (key path, YAML text) pairs, as Python's wrapper passes `overrides`.
using KeyValues = std::vector<std::pair<std::string, std::string>>;

std::vector<Override> AsOverrides(const KeyValues& pairs,
                                  const std::string& flag_prefix) {
  std::vector<Override> out;
  for (const auto& [key, value] : pairs) {
    // A section after a key in it would drop the key in silence, as two
    // --set flags would.
    Override o{flag_prefix + key, key, value};
    RefuseUndoing(o, out);
    out.push_back(std::move(o));
  }
  return out;
}

// The moves of the next step, set from Python.
class ExternalPolicy : public NamedPolicy<ExternalPolicy> {
 public:
  static constexpr std::string_view kName = "python";
  void Reset(const Map&, int, int, std::uint64_t) override {}
  PolicyStatus Decide(const DecisionContext&,
                      std::vector<Move>* moves) override {
    *moves = next;
    return PolicyStatus::kOk;
  }
  std::vector<Move> next;
};

// ---------------------------------------------------------------------------
// Input from Python: every bad value is one aia.InputError (a ValueError)
// that names the Python callable and argument, "aia.Mission.step: moves[2]:
// must be 0 (left), ..., got 1.7 (float)"; nothing is converted silently.

[[noreturn]] void Refuse(const std::string& where, const std::string& arg,
                         const std::string& what) {
  throw InputError(where, 0, arg, what);
}

// One call at a time on an object whose calls release the GIL (Mission,
// VectorMissions, Dataset): a call from a second thread while one is inside
// is refused, as a gymnasium env is used from one thread at a time, instead
// of racing the first (which crashed the process). `*busy` names the call
// inside (null: none); it is set and cleared with the GIL held, so the GIL
// orders it.
class CallGuard {
 public:
  CallGuard(const char** busy, const char* where) : busy_(busy) {
    if (*busy != nullptr)
      Refuse(where, "",
             std::string("another thread is inside ") + *busy +
                 " on this object, which takes one call at a time (as a "
                 "gymnasium env does): give each thread its own, or take "
                 "turns with a lock");
    *busy = where;
  }
  ~CallGuard() { *busy_ = nullptr; }
  CallGuard(const CallGuard&) = delete;
  CallGuard& operator=(const CallGuard&) = delete;

 private:
  const char** busy_;
};

// A method of C as a binding that holds C's CallGuard for the call.
template <typename C, typename R, typename... A>
auto OneCall(R (C::*f)(A...), const char* where) {
  return [f, where](C& self, A... a) -> R {
    CallGuard guard(self.busy(), where);
    return (self.*f)(std::forward<A>(a)...);
  };
}
template <typename C, typename R, typename... A>
auto OneCall(R (C::*f)(A...) const, const char* where) {
  return [f, where](const C& self, A... a) -> R {
    CallGuard guard(self.busy(), where);
    return (self.*f)(std::forward<A>(a)...);
  };
}

// ---------------------------------------------------------------------------
// The GIL let go for C++ work, and the interpreter's exit. A daemon thread
// inside such a call when the interpreter finalizes is ended by CPython
// (pthread_exit) as it takes the GIL back: a forced unwind from inside
// PyEval_RestoreThread, which must be able to leave the frames above it, as
// it leaves CPython's own (pybind11's dispatcher lets it through). Through
// pybind11's gil_scoped_release, whose destructor is noexcept, it aborted
// the process ("terminate called without an active exception").

// Whether this thread is running a policy's callbacks for aia.evaluate (one
// of the evaluation's threads, the GIL taken for the call): an
// aia.evaluate called there is refused.
thread_local bool t_inside_evaluate = false;

// aia.evaluate calls running (their handler for Ctrl-C installed), and
// whether the interpreter's exit has begun (StopEvaluationsAtExit).
std::atomic<int> g_evaluations{0};
std::atomic<bool> g_exiting{false};

// Python's atexit handler (registered at import): an aia.evaluate still
// running on another thread (a daemon thread's) is stopped as Ctrl-C stops
// it, after the runs under way, their rows written, so that the exit waits
// for those runs only and finalization does not meet its threads; without
// the GIL, which its policy's callbacks need until they stop.
void StopEvaluationsAtExit() {
  g_exiting = true;
  py::gil_scoped_release release;
  while (g_evaluations.load() > 0) {
    RequestInterrupt();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

// Whether the interpreter is finalizing (a thread other than the
// finalizing one that takes the GIL is ended).
bool Finalizing() {
#if PY_VERSION_HEX >= 0x030D0000
  return Py_IsFinalizing() != 0;
#else
  return _Py_IsFinalizing() != 0;
#endif
}

// py::gil_scoped_release for the module's calls, but a destructor that the
// thread's end may leave by a forced unwind (above). Not to be left by an
// exception of the scope's own while finalization ends the thread.
class ReleaseGil {
 public:
  ReleaseGil() : state_(PyEval_SaveThread()) {}
  ~ReleaseGil() noexcept(false) { PyEval_RestoreThread(state_); }
  ReleaseGil(const ReleaseGil&) = delete;
  ReleaseGil& operator=(const ReleaseGil&) = delete;

 private:
  PyThreadState* state_;
};

// A value that holds Python objects, kept through a ReleaseGil scope on
// the heap: a thread that finalization ends inside the scope (above)
// unwinds through no Python object, whose release without the GIL touched
// an interpreter being finalized (a segfault at exit, about once in 60
// runs of a daemon thread stepping an autoresetting VectorMissions on two
// busy cores). It is leaked then, as the process ends; an exception of the
// scope's own, which leaves it with the GIL back, releases it.
template <typename T>
class Held {
 public:
  explicit Held(T value) : value_(new T(std::move(value))) {}
  ~Held() {
    if (value_ != nullptr && PyGILState_Check()) delete value_;
  }
  Held(const Held&) = delete;
  Held& operator=(const Held&) = delete;
  T& get() { return *value_; }
  // The value back (once, with the GIL).
  T Take() {
    T value = std::move(*value_);
    delete value_;
    value_ = nullptr;
    return value;
  }

 private:
  T* value_;
};

// py::gil_scoped_acquire on aia.evaluate's own threads, whose pool would
// stop a forced unwind: during finalization such a thread waits, without
// the GIL, until the process ends.
class AcquireGil {
 public:
  AcquireGil() {
    if (Finalizing())
      for (;;) std::this_thread::sleep_for(std::chrono::hours(1));
    acquire_.emplace();
  }
  AcquireGil(const AcquireGil&) = delete;
  AcquireGil& operator=(const AcquireGil&) = delete;

 private:
  std::optional<py::gil_scoped_acquire> acquire_;
};

// A Python value as an error shows it: its repr (cut short) and its type.
std::string Shown(py::handle h) {
  std::string text;
  try {
    text = py::repr(h).cast<std::string>();
  } catch (const py::error_already_set&) {
    text = "?";
  }
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return text + " (" + Py_TYPE(h.ptr())->tp_name + ")";
}

bool IsBool(py::handle h) {
  if (PyBool_Check(h.ptr())) return true;
  static const py::handle numpy_bool =
      py::object(py::module_::import("numpy").attr("bool_")).release();
  return PyObject_IsInstance(h.ptr(), numpy_bool.ptr()) == 1;
}

// An integer from Python (an int, a numpy integer, an aia.Move), or
// nullptr for anything else: bools, floats (NaN and inf too), strings.
py::object AsInteger(py::handle h) {
  if (IsBool(h) || PyFloat_Check(h.ptr()) || !PyIndex_Check(h.ptr()))
    return py::object();
  PyObject* i = PyNumber_Index(h.ptr());
  if (i == nullptr) {
    PyErr_Clear();
    return py::object();
  }
  return py::reinterpret_steal<py::object>(i);
}

// An integer argument in [lo, hi].
long long IntegerArg(py::handle h, const std::string& where,
                     const std::string& arg, long long lo, long long hi) {
  const py::object i = AsInteger(h);
  if (!i)
    Refuse(where, arg,
           "must be an integer in [" + std::to_string(lo) + ", " +
               std::to_string(hi) + "], got " + Shown(h));
  int overflow = 0;
  const long long v = PyLong_AsLongLongAndOverflow(i.ptr(), &overflow);
  if (overflow != 0 || v < lo || v > hi)
    Refuse(where, arg,
           "must be an integer in [" + std::to_string(lo) + ", " +
               std::to_string(hi) + "], got " + py::str(i).cast<std::string>());
  return v;
}

// A seed: an integer in [0, 2^64 - 1]; None when `none_ok` (the file's).
std::optional<std::uint64_t> SeedArg(py::handle h, const std::string& where,
                                     const std::string& arg, bool none_ok) {
  if (none_ok && h.is_none()) return std::nullopt;
  const std::string expect =
      std::string("must be an integer in [0, 2^64 - 1]") +
      (none_ok ? " or None" : "");
  const py::object i = AsInteger(h);
  if (!i) Refuse(where, arg, expect + ", got " + Shown(h));
  const unsigned long long v = PyLong_AsUnsignedLongLong(i.ptr());
  if (PyErr_Occurred()) {
    PyErr_Clear();
    Refuse(where, arg, expect + ", got " + py::str(i).cast<std::string>());
  }
  return static_cast<std::uint64_t>(v);
}

std::string ShapeText(const std::vector<py::ssize_t>& shape) {
  std::string out = "(";
  for (std::size_t k = 0; k < shape.size(); ++k) {
    if (k) out += ", ";
    out += shape[k] < 0 ? std::string("any") : std::to_string(shape[k]);
  }
  return out + (shape.size() == 1 ? ",)" : ")");
}

// The integers of a Python list, tuple or numpy array of exactly `shape`
// (-1: any length), each in [lo, hi], flat in C order. `expect` says what
// one is ("0 (left), ..."), `shape_name` what the shape means.
std::vector<long long> Integers(
    py::handle obj, const std::vector<py::ssize_t>& shape, long long lo,
    long long hi, const std::string& where, const std::string& arg,
    const std::string& expect, const std::string& shape_name) {
  static const py::handle numpy = py::module_::import("numpy").release();
  const bool is_array = py::isinstance<py::array>(obj);
  if (!is_array && !PyList_Check(obj.ptr()) && !PyTuple_Check(obj.ptr()))
    Refuse(where, arg,
           "must be a list or numpy array of integers (" + shape_name +
               "), each " + expect + ", got " + Shown(obj));
  py::array a;
  try {
    // A list's own items (object dtype): numpy would make True into 1.
    a = is_array ? py::reinterpret_borrow<py::array>(obj)
                 : py::array(numpy.attr("asarray")(
                       obj, py::arg("dtype") = py::dtype("O")));
  } catch (const py::error_already_set&) {
    Refuse(where, arg, "must be " + shape_name + ", got " + Shown(obj));
  }
  std::vector<py::ssize_t> got(a.shape(), a.shape() + a.ndim());
  bool fits = got.size() == shape.size();
  for (std::size_t k = 0; fits && k < shape.size(); ++k)
    fits = shape[k] < 0 || got[k] == shape[k];
  if (!fits)
    Refuse(where, arg,
           "must have shape " + ShapeText(shape) + ", " + shape_name +
               ", got shape " + ShapeText(got));
  const char kind = a.dtype().kind();
  if (kind != 'i' && kind != 'u' && kind != 'O')
    Refuse(where, arg,
           "must be integers, each " + expect + ", got an array of " +
               py::str(a.dtype()).cast<std::string>());
  // "[i][j]" of the flat element k, for an error.
  const auto index_of = [&got](std::size_t k) {
    std::vector<std::size_t> at(got.size());
    for (std::size_t d = got.size(); d-- > 0;) {
      at[d] = k % static_cast<std::size_t>(got[d]);
      k /= static_cast<std::size_t>(got[d]);
    }
    std::string index;
    for (std::size_t d : at) index += "[" + std::to_string(d) + "]";
    return index;
  };
  // An integer array whose values fit int64: read as such (no Python
  // object per element).
  if (kind == 'i' || (kind == 'u' && a.dtype().itemsize() < 8)) {
    const auto c = py::array_t<long long, py::array::c_style |
                                              py::array::forcecast>::ensure(a);
    if (c) {
      const long long* v = c.data();
      for (py::ssize_t k = 0; k < c.size(); ++k)
        if (v[k] < lo || v[k] > hi)
          Refuse(where, arg + index_of(static_cast<std::size_t>(k)),
                 "must be " + expect + ", got " + std::to_string(v[k]));
      return std::vector<long long>(v, v + c.size());
    }
    PyErr_Clear();
  }
  const py::list items = a.attr("ravel")().attr("tolist")();
  std::vector<long long> out;
  out.reserve(items.size());
  for (std::size_t k = 0; k < items.size(); ++k) {
    const py::object i = AsInteger(items[k]);
    if (!i)
      Refuse(where, arg + index_of(k),
             "must be " + expect + ", got " + Shown(items[k]));
    int overflow = 0;
    const long long v = PyLong_AsLongLongAndOverflow(i.ptr(), &overflow);
    if (overflow != 0 || v < lo || v > hi)
      Refuse(where, arg + index_of(k),
             "must be " + expect + ", got " + py::str(i).cast<std::string>());
    out.push_back(v);
  }
  return out;
}

constexpr const char* kMoveText =
    "0 (left), 1 (right), 2 (up), 3 (down) or 4 (stay)";

// One move per robot of each of `shape`'s rows, from Python.
std::vector<Move> MovesFrom(py::handle moves,
                            const std::vector<py::ssize_t>& shape,
                            const std::string& where,
                            const std::string& arg = "moves") {
  const std::string shape_name =
      shape.size() == 1 ? "one move per robot"
                        : "(missions, robots): one move per robot and mission";
  const std::vector<long long> v =
      Integers(moves, shape, 0, 4, where, arg, kMoveText, shape_name);
  std::vector<Move> out(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) out[i] = static_cast<Move>(v[i]);
  return out;
}

// An error of aia's command-line core (flags, `--set`) as Python's: the
// callable instead of "command line", the argument instead of the flag.
InputError Renamed(const InputError& e, const std::string& where) {
  if (e.file() != "command line") return e;
  std::string key = e.key();
  static const std::vector<std::pair<std::string, std::string>> kFlags = {
      {"--set ", "overrides: "}, {"--seed-base", "seed_base"},
      {"--sizes", "sizes"},      {"--seeds", "seeds"},
      {"--threads", "threads"},  {"--out", "out"}};
  for (const auto& [flag, name] : kFlags)
    if (key.compare(0, flag.size(), flag) == 0) {
      key = name + key.substr(flag.size());
      break;
    }
  // The flags the message names, as the arguments they are in Python.
  static const std::vector<std::pair<std::string, std::string>> kWords = {
      {"--seed-base", "seed_base"},
      {"--sizes", "sizes"},
      {"--seeds", "seeds"},
      {"--threads", "threads"},
      {"--out", "out"},
      {"--set", "overrides"},
      {"--policies", "name"}};
  std::string message = e.message();
  for (const auto& [flag, name] : kWords)
    for (std::size_t at = message.find(flag); at != std::string::npos;
         at = message.find(flag, at)) {
      const std::size_t end = at + flag.size();
      if (end < message.size() &&
          (std::isalnum(static_cast<unsigned char>(message[end])) ||
           message[end] == '-')) {
        at = end;  // a longer flag
        continue;
      }
      message.replace(at, flag.size(), name);
      at += name.size();
    }
  return InputError(where, 0, key, message);
}

template <typename T>
py::array_t<T> Array(std::vector<py::ssize_t> shape) {
  return py::array_t<T>(shape);
}

// Channel settings from Python (key, YAML text) pairs, read as a model's
// metadata is, errors naming `where`: `aia.Dataset: channels: window: must
// be an integer in [4, 512], got 2`.
ChannelParams ChannelSettings(const KeyValues& params,
                              const std::string& where) {
  ChannelParams settings;
  try {
    ConfigNode node = ConfigNode::Map();
    for (const auto& [key, value] : params)
      node.Set(key, ParseYamlValue(value, "channels: " + key));
    ReadFields(node, ReadOptions{"channels", "", ""}, "", &settings);
  } catch (const InputError& e) {
    throw InputError(
        where, 0,
        e.key().rfind("channels: ", 0) == 0 ? e.key() : "channels: " + e.key(),
        e.message());
  }
  // As a model's metadata: a setting without the one it needs is refused,
  // not ignored.
  if (const auto [key, needs] = settings.MissingPrerequisite(); !key.empty())
    Refuse(where, "channels: " + std::string(key),
           "needs " + std::string(needs) + " (as in a model's metadata)");
  return settings;
}

std::atomic<std::uint64_t> g_next_mission_id{1};

// Every aia.builtin_policy's per-mission states, so that a mission that
// ends (deleted, restarted, its evaluation run over) is dropped by all of
// them at once: a policy keeps each live mission's state however many take
// turns. The lock serializes the states' maps: missions restart on
// VectorMissions' worker threads without the GIL.
struct LiveStates {
  std::mutex mu;
  std::set<PolicyStates*> all;
};
LiveStates& Live() {
  static LiveStates* live = new LiveStates;  // outlives the module's statics
  return *live;
}
void MissionEnded(std::uint64_t id) {
  if (id == 0) return;
  LiveStates& live = Live();
  const std::lock_guard<std::mutex> lock(live.mu);
  for (PolicyStates* s : live.all) s->Drop(id);
}

// What one step did (Mission.step), as Gymnasium tells it: `terminated`
// when the mission reached an end state (success, or no robot left),
// `truncated` when it was cut short (mission.max_steps).
struct StepResult {
  int steps = 0;           // decision steps taken so far
  long invalid_moves = 0;  // moves the world rule replaced at this step
  int localized = 0;       // targets below eps in the team's best estimate
  bool terminated = false;
  bool truncated = false;
  bool success = false;
  bool done() const { return terminated || truncated; }
};

// One mission, owned (its own episode, stepped from Python) or a view of a
// decision inside aia's own loop (evaluate), valid during that call only.
class Mission {
 public:
  Mission(std::string scenario, std::optional<std::uint64_t> seed,
          KeyValues overrides)
      : scenario_(ReadScenarioSource(scenario)),
        overrides_(std::move(overrides)) {
    Start(seed);
  }
  Mission(const DecisionContext* view, std::uint64_t seed, std::uint64_t id,
          int max_steps)
      : id_(id), view_(view), seed_(seed), max_steps_(max_steps) {}

  // (Re)starts the owned mission at `seed` (the file's when none): step 0,
  // a new id (a builtin policy begins afresh on it). Errors leave the
  // mission as it was. Touches no Python object (runs on worker threads).
  void Start(std::optional<std::uint64_t> seed) {
    std::vector<Override> all;
    if (seed) all.push_back({"seed", "seed", std::to_string(*seed)});
    for (const Override& o : AsOverrides(overrides_, "overrides: "))
      all.push_back(o);
    // The file as it was read when the mission was made.
    const Scenario scenario = LoadScenario(scenario_, all);
    std::shared_ptr<const Instance> instance = BuildInstance(scenario);
    scenario_warnings_ = scenario.warnings;
    // What refers to the old episode goes first.
    picture_.reset();
    renderer_.reset();
    channel_renderer_.reset();
    picture_added_ = false;
    picture_width_ = picture_height_ = 0;
    episode_.reset();
    search_points_.reset();
    search_step_ = -1;
    instance_ = std::move(instance);
    auto policy = std::make_unique<ExternalPolicy>();
    external_ = policy.get();
    episode_ = std::make_unique<Episode>(instance_, std::move(policy));
    moves_ = std::make_unique<MoveObserver>();
    estimate_ = std::make_unique<EstimateObserver>();
    episode_->AddObserver(moves_.get());
    episode_->AddObserver(estimate_.get());
    moves_->OnStart(*episode_);
    estimate_->OnStart(*episode_);
    seed_ = episode_->scenario().seed;
    max_steps_ = episode_->mission().max_steps;
    MissionEnded(id_);
    id_ = g_next_mission_id++;
  }
  ~Mission() {
    if (owned()) MissionEnded(id_);
  }
  Mission(const Mission&) = delete;
  Mission& operator=(const Mission&) = delete;

  bool owned() const { return episode_ != nullptr; }
  bool in_vector() const { return in_vector_; }
  // One of a VectorMissions: stepped and restarted by it only.
  void MarkInVector() { in_vector_ = true; }
  // The decision is over: the view reads nothing after this. A call still
  // in flight on it (another thread inside channels() or a policy's
  // decide, the GIL released) is waited for first, with the GIL let go
  // while waiting; the caller holds the GIL, as every CallGuard does when
  // it marks and clears busy_, so reading it here is no race.
  void Invalidate() {
    while (busy_ != nullptr) {
      ReleaseGil release;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    view_ = nullptr;
  }
  const char** busy() const { return &busy_; }
  std::uint64_t id() const { return id_; }
  // The scenario's warnings (keys that change nothing where they stand),
  // "FILE:LINE: key: what"; Python's Mission raises them as
  // aia.ScenarioWarning.
  const std::vector<std::string>& scenario_warnings() const {
    return scenario_warnings_;
  }
  std::uint64_t seed() const { return seed_; }
  int max_steps() const {
    if (!owned())
      Refuse("aia.Mission.max_steps", "",
             "a mission seen by a policy inside aia.evaluate has none of "
             "its own: aia.evaluate ends each run at its horizon (3 F*, or "
             "the scenario's mission.max_steps where there is no F*)");
    return max_steps_;
  }
  // What a policy is given now (the team's belief included).
  DecisionContext Context() const {
    if (owned()) return episode_->Context();
    if (view_ == nullptr)
      Refuse("aia.Mission", "",
             "this mission is a view of one decision of aia.evaluate: it is "
             "valid only inside the policy's call");
    return *view_;
  }
  // The owned episode; `where` is the call that needs it.
  const Episode& episode(const char* where = "aia.Mission") const {
    if (!owned())
      Refuse(where, "",
             "a mission seen by a policy inside aia.evaluate can only be "
             "read (state(), num_robots, ...): aia steps it, and its "
             "summary, diagnostics and frames are aia.evaluate's");
    return *episode_;
  }
  int num_robots() const {
    return static_cast<int>(Context().robot_lattice->size());
  }
  int num_targets() const { return Context().beliefs->layout().num_targets(); }
  // mission.decisions async.
  bool asynchronous() const { return Context().ready != nullptr; }
  int step() const { return Context().step; }
  bool done() const { return owned() && episode_->done(); }
  bool success() const { return owned() && episode_->success(); }
  int flowtime() const { return owned() ? episode_->flowtime() : -1; }

  // What the robots know (the context's arrays), and for an owned mission
  // the ground truth apart.
  py::dict State() const {
    const DecisionContext ctx = Context();
    const int n = num_robots(), m = num_targets();
    const Lattice& lattice = ctx.map->lattice();
    auto positions = Array<double>({n, 2});
    auto headings = Array<double>({n});
    auto lattice_index = Array<long long>({n});
    auto cells = Array<long long>({n, 2});
    auto active = Array<bool>({n});
    auto neighbors = Array<bool>({n, n});
    auto mean = Array<double>({n, m, 2});
    auto cov = Array<double>({n, m, 2, 2});
    auto det = Array<double>({n, m});
    auto log_det_prior = Array<double>({m});
    auto p = positions.mutable_unchecked<2>();
    auto h = headings.mutable_unchecked<1>();
    auto li = lattice_index.mutable_unchecked<1>();
    auto c = cells.mutable_unchecked<2>();
    auto a = active.mutable_unchecked<1>();
    auto g = neighbors.mutable_unchecked<2>();
    auto mu = mean.mutable_unchecked<3>();
    auto sigma = cov.mutable_unchecked<4>();
    auto d = det.mutable_unchecked<2>();
    auto prior = log_det_prior.mutable_unchecked<1>();
    const BeliefSet& beliefs = *ctx.beliefs;
    for (int i = 0; i < n; ++i) {
      const int q = (*ctx.robot_lattice)[i];
      const Vec2 x =
          ctx.robot_positions ? (*ctx.robot_positions)[i] : lattice.Point(q);
      p(i, 0) = x.x();
      p(i, 1) = x.y();
      h(i) = ctx.robot_headings ? (*ctx.robot_headings)[i] : 0.0;
      li(i) = q;
      c(i, 0) = lattice.Ix(q);
      c(i, 1) = lattice.Iy(q);
      a(i) = ctx.comm->Active(i);
      for (int j = 0; j < n; ++j) g(i, j) = false;
      for (int j : ctx.comm->Neighbors(i)) g(i, j) = true;
      for (int k = 0; k < m; ++k) {
        const Vec2 xk = beliefs.PositionMean(i, k);
        const Mat2 s = beliefs.PositionCovariance(i, k);
        mu(i, k, 0) = xk.x();
        mu(i, k, 1) = xk.y();
        for (int r = 0; r < 2; ++r)
          for (int col = 0; col < 2; ++col) sigma(i, k, r, col) = s(r, col);
        d(i, k) = beliefs.DetCovariance(i, k);
      }
    }
    for (int k = 0; k < m; ++k)
      prior(k) = ctx.log_det_prior ? (*ctx.log_det_prior)[k] : 0.0;
    py::dict state;
    state["steps"] = ctx.step;
    state["positions"] = positions;
    state["headings"] = headings;
    state["lattice"] = lattice_index;
    state["cells"] = cells;
    state["active"] = active;
    state["neighbors"] = neighbors;
    state["mean"] = mean;
    state["cov"] = cov;
    state["det"] = det;
    state["log_det_prior"] = log_det_prior;
    state["eps"] = ctx.eps;
    state["workspace"] =
        py::make_tuple(ctx.map->size().x(), ctx.map->size().y());
    if (owned()) {
      auto truth_positions = Array<double>({m, 2});
      auto t = truth_positions.mutable_unchecked<2>();
      for (int k = 0; k < m; ++k) {
        t(k, 0) = episode_->target_positions()[k].x();
        t(k, 1) = episode_->target_positions()[k].y();
      }
      py::dict truth;
      truth["target_positions"] = truth_positions;
      state["truth"] = truth;
    }
    return state;
  }

  // I-GBNet's input of every robot, (N, C, H, W) float32, from the C++
  // renderer (learning/channels.h) with these channel settings; the heat of
  // each robot's own fused belief, its neighbours from this step's graph,
  // the trail from its last applied move, and the search points (made of
  // every step's misses, so kept from step 0 on once asked for) as the
  // igbnet policy makes them.
  py::array_t<float> Channels(const KeyValues& params) {
    ChannelJob job = PrepareChannels(params, "aia.Mission.channels");
    py::array_t<float> out(job.Shape(num_robots()));
    float* data = out.mutable_data();
    Held<py::array_t<float>> held(std::move(out));
    {
      ReleaseGil release;
      RenderChannels(job, data);
    }
    return held.Take();
  }

  // What one channels() call renders with: its settings and renderer (the
  // mission's kept one, or `made` for a view), found with the GIL held.
  struct ChannelJob {
    ChannelParams settings;
    std::unique_ptr<ChannelRenderer> made;
    ChannelRenderer* renderer = nullptr;

    std::vector<py::ssize_t> Shape(int robots) const {
      return {static_cast<py::ssize_t>(robots),
              static_cast<py::ssize_t>(renderer->channels()),
              static_cast<py::ssize_t>(renderer->height()),
              static_cast<py::ssize_t>(renderer->width())};
    }
  };
  ChannelJob PrepareChannels(const KeyValues& params, const char* where) {
    ChannelJob job;
    job.settings = ChannelSettings(params, where);
    if (job.settings.search && !search_points_) {
      if (!owned())
        Refuse(where, "search",
               "a mission seen by a policy inside aia.evaluate keeps no "
               "search points (they are made of every step's misses)");
      if (step() != 0)
        Refuse(where, "search",
               "the search points are made of every step's misses since "
               "the start: ask for them first at step 0 of a mission (this "
               "one is at step " +
                   std::to_string(step()) + ")");
      search_points_.emplace();
      search_points_->Reset(num_robots(), num_targets());
    }
    const DecisionContext ctx = Context();
    const Map& map = *ctx.map;
    const Lattice& lattice = map.lattice();
    // As the igbnet policy renders them: one pixel per lattice step, and
    // observation pixels within the sensor's range.
    const ChannelParams at_step =
        ctx.sensor ? AtSensorRange(AtLatticeStep(job.settings, lattice.step()),
                                   ctx.sensor->range)
                   : AtLatticeStep(job.settings, lattice.step());
    // One renderer kept for the settings last asked for, as the policy keeps
    // its own (making it each call was a third of a call: 0.6 ms, some 15 %
    // of a 10 x 10 env step); a view's world is not kept.
    if (!(owned() && channel_renderer_ && channel_key_ == params)) {
      if (const std::string why = ChannelGridProblem(map.size(), at_step);
          !why.empty())
        Refuse(where, "", why);
      job.made = std::make_unique<ChannelRenderer>(map.occupancy(), map.size(),
                                                   at_step, &lattice);
      if (owned()) {
        channel_renderer_ = std::move(job.made);
        channel_key_ = params;
      }
    }
    job.renderer = job.made ? job.made.get() : channel_renderer_.get();
    return job;
  }
  // Renders every robot's channels into `data` (Shape's size): no Python,
  // so on any thread without the GIL, one call per mission at a time.
  void RenderChannels(const ChannelJob& job, float* data) {
    if (job.settings.search) SyncSearchPoints();
    const DecisionContext ctx = Context();
    const Lattice& lattice = ctx.map->lattice();
    ChannelRenderer& renderer = *job.renderer;
    std::vector<Vec2> neighbours;
    std::vector<HeatSource> targets;
    const std::vector<double> no_prior(num_targets(), 0.0);
    const std::vector<double>& prior =
        ctx.log_det_prior ? *ctx.log_det_prior : no_prior;
    SearchPointSets points;
    for (int i = 0; i < num_robots(); ++i) {
      neighbours.clear();
      for (int j : ctx.comm->Neighbors(i))
        if (j != i)
          neighbours.push_back(lattice.Point((*ctx.robot_lattice)[j]));
      HeatSources(*ctx.beliefs, i, &targets);
      const int here = (*ctx.robot_lattice)[i];
      RobotMemory memory;
      SetTrail(lattice, here, ctx.history ? ctx.history->last(i) : Move::kStay,
               &memory);
      if (job.settings.search)
        SetSearchPoints(*search_points_, i, &points, &memory);
      renderer.Render(lattice.Point(here), neighbours, targets, prior, ctx.eps,
                      data + i * renderer.ImageSize(), memory);
    }
  }
  // The search points brought to this step (once per step, in order, as the
  // policy records them); owned missions that asked for them.
  void SyncSearchPoints() {
    if (!search_points_ || search_step_ == step()) return;
    const DecisionContext ctx = episode_->Context();
    search_rows_.clear();
    for (int i = 0; i < num_robots(); ++i)
      if (ctx.comm->Active(i)) search_rows_.push_back(i);
    RecordSearchPoints(ctx, search_rows_, &*search_points_, &search_deciding_);
    search_step_ = step();
  }

  // An RGB frame (H, W, 3) of the physics now with aia render's overlays.
  // The renderer is made at the first call (and again for another size);
  // the trails start there.
  py::array_t<std::uint8_t> Render(py::handle width_arg,
                                   py::handle height_arg) {
    const Episode& e = episode("aia.Mission.render");  // owned only
    if (const std::string why = RenderForkProblem(); !why.empty())
      Refuse("aia.Mission.render", "", why);
    const int width = static_cast<int>(
        IntegerArg(width_arg, "aia.Mission.render", "width", 16, 8192));
    const int height = static_cast<int>(
        IntegerArg(height_arg, "aia.Mission.render", "height", 16, 8192));
    if (!picture_ || width != picture_width_ || height != picture_height_) {
      picture_.reset();
      FrameSettings settings;
      settings.scene.width = width;
      settings.scene.height = height;
      renderer_ =
          std::make_unique<FrameRenderer>(e.sim(), e.world().map, settings);
      picture_ = std::make_unique<PictureObserver>(e, renderer_.get());
      if (!picture_added_) {
        episode_->AddObserver(&picture_forward_);
        picture_added_ = true;
      }
      picture_width_ = width;
      picture_height_ = height;
    }
    const cv::Mat& bgr = picture_->picture.Render(e);
    py::array_t<std::uint8_t> out({static_cast<py::ssize_t>(bgr.rows),
                                   static_cast<py::ssize_t>(bgr.cols),
                                   static_cast<py::ssize_t>(3)});
    auto v = out.mutable_unchecked<3>();
    for (int y = 0; y < bgr.rows; ++y) {
      const std::uint8_t* row = bgr.ptr<std::uint8_t>(y);
      for (int x = 0; x < bgr.cols; ++x)
        for (int c = 0; c < 3; ++c) v(y, x, c) = row[3 * x + 2 - c];
    }
    return out;
  }

  // (N,): which robots' moves the next step uses: all of them in lockstep;
  // with mission.decisions async those whose last move has ended (the
  // others drive on, whatever step() is given for them).
  py::array_t<bool> Ready() const {
    const DecisionContext ctx = Context();
    const int n = num_robots();
    auto out = Array<bool>({n});
    auto v = out.mutable_unchecked<1>();
    for (int i = 0; i < n; ++i) v(i) = Deciding(ctx, i);
    return out;
  }

  // (N, 4): which of each robot's moves stay on the lattice.
  py::array_t<bool> ValidMoves() const {
    const DecisionContext ctx = Context();
    const Lattice& lattice = ctx.map->lattice();
    const int n = num_robots();
    auto out = Array<bool>({n, kNumMoves});
    auto v = out.mutable_unchecked<2>();
    for (int i = 0; i < n; ++i)
      for (int a = 0; a < kNumMoves; ++a)
        v(i, a) = lattice.Valid((*ctx.robot_lattice)[i], static_cast<Move>(a));
    return out;
  }

  StepResult Step(py::handle moves) {
    if (in_vector_)
      Refuse("aia.Mission.step", "",
             "this mission is one of an aia.VectorMissions, whose missions "
             "step together: VectorMissions.step");
    std::vector<Move> next =
        MovesFrom(moves, {num_robots()}, "aia.Mission.step");
    if (episode("aia.Mission.step").done())
      Refuse("aia.Mission.step", "moves",
             "the mission is done (done is True): start another Mission");
    const long invalid_before = episode_->invalid_moves();
    {
      ReleaseGil release;
      StepWith(std::move(next));
    }
    return Result(invalid_before);
  }
  // One step with these moves (owned missions, not done; no Python object
  // touched).
  void StepWith(std::vector<Move> moves) {
    SyncSearchPoints();  // the state these moves were decided at
    external_->next = std::move(moves);
    episode_->Step();
    if (episode_->done()) {
      moves_->OnEnd(*episode_);
      estimate_->OnEnd(*episode_);
    }
  }
  // The last step's result, the world rule having replaced
  // invalid_moves() - `invalid_before` of its moves.
  StepResult Result(long invalid_before) const {
    const Episode& e = *episode_;
    StepResult r;
    r.steps = e.step();
    r.invalid_moves = e.invalid_moves() - invalid_before;
    r.localized = e.NumLocalized();
    r.success = e.success();
    if (e.done()) {
      const DecisionContext ctx = e.Context();
      bool any_active = false;
      for (int i = 0; i < num_robots(); ++i)
        any_active = any_active || ctx.comm->Active(i);
      // Ended by success only where success ends it (a tracking mission,
      // stop_at_success false, runs to its horizon: truncated there).
      r.terminated =
          (e.success() && e.mission().stop_at_success) || !any_active;
      r.truncated = !r.terminated;
    }
    return r;
  }

  std::string SummaryText() const {
    const Episode& e = episode("aia.Mission.summary");
    return SummaryJson(Summarize(e, 0.0), e);
  }
  std::string DiagnosticsText() const {
    return DiagnosticsJson(episode("aia.Mission.diagnostics"), *moves_,
                           *estimate_, 0.0);
  }

 private:
  ScenarioSource scenario_;
  bool in_vector_ = false;  // VectorMissions steps and restarts it
  KeyValues overrides_;
  std::vector<std::string> scenario_warnings_;
  std::uint64_t id_ = 0;
  const DecisionContext* view_ = nullptr;
  std::uint64_t seed_ = 0;
  int max_steps_ = 0;
  std::shared_ptr<const Instance> instance_;
  // Channels' renderer, for the settings channel_key_ (reset with the world).
  std::unique_ptr<ChannelRenderer> channel_renderer_;
  KeyValues channel_key_;
  ExternalPolicy* external_ = nullptr;  // owned by the episode
  std::unique_ptr<Episode> episode_;
  std::unique_ptr<MoveObserver> moves_;
  std::unique_ptr<EstimateObserver> estimate_;
  // channels(search=True): the robots' search points, brought to step
  // search_step_ (-1: none yet).
  std::optional<SearchPoints> search_points_;
  int search_step_ = -1;
  std::vector<int> search_rows_, search_deciding_;
  // render(): the picture kept in step with the episode once made.
  struct PictureObserver {
    PictureObserver(const Episode& e, FrameRenderer* renderer)
        : picture(e, renderer) {
      picture.AfterStep(e);
    }
    EpisodePicture picture;
  };
  struct PictureForward : StepObserver {
    explicit PictureForward(Mission* m) : mission(m) {}
    ObserverStatus OnStep(const Episode& e) override {
      if (mission->picture_) mission->picture_->picture.AfterStep(e);
      return ObserverStatus::kContinue;
    }
    Mission* mission;
  };
  std::unique_ptr<FrameRenderer> renderer_;
  std::unique_ptr<PictureObserver> picture_;
  PictureForward picture_forward_{this};
  bool picture_added_ = false;
  int picture_width_ = 0, picture_height_ = 0;
  mutable const char* busy_ = nullptr;  // CallGuard
};

// A registered policy deciding on a mission's current state.
class BuiltinPolicy {
 public:
  BuiltinPolicy(const std::string& name, const KeyValues& params) {
    std::vector<Override> o = {{"name", "policy.name", name}};
    for (const Override& p : AsOverrides(params, ""))
      o.push_back({p.flag, "policy." + p.path, p.value});
    const PolicyRegistry registry = AllPolicies();
    if (!registry.Has(name))
      Refuse("aia.builtin_policy", "name", registry.UnknownPolicy(name));
    // On any valid scenario: only its policy section is read.
    try {
      spec_ = registry.Resolve(WithOverrides(GeneratedScenario(1, 1, 0), o));
    } catch (const InputError& e) {
      throw Renamed(e, "aia.builtin_policy");
    }
    LiveStates& live = Live();
    const std::lock_guard<std::mutex> lock(live.mu);
    live.all.insert(&states_);
  }
  ~BuiltinPolicy() {
    LiveStates& live = Live();
    const std::lock_guard<std::mutex> lock(live.mu);
    live.all.erase(&states_);
  }
  BuiltinPolicy(const BuiltinPolicy&) = delete;
  BuiltinPolicy& operator=(const BuiltinPolicy&) = delete;

  const std::string& name() const { return spec_->name(); }
  bool centralized() const { return spec_->centralized(); }

  // One move per robot from what the robots know at this step (the team's
  // belief only for a centralized policy). Each mission has its own policy
  // state, started afresh (Reset with the mission's seed) at its first
  // decision or at a round that is not the next one (DecisionContext::
  // round: in async the step may repeat), so that deciding at every round
  // repeats `aia run`, also with missions on several threads (evaluate). Called
  // with the GIL held; the decision runs without it.
  py::array_t<long long> Decide(const Mission& mission) {
    CallGuard guard(mission.busy(), "aia.builtin_policy.decide");
    DecisionContext ctx = mission.Context();
    std::shared_ptr<PolicyStates::Entry> state;
    {
      const std::lock_guard<std::mutex> lock(Live().mu);
      state = states_.For(mission.id(), ctx.round, [&] {
        std::unique_ptr<Policy> policy = spec_->Create();
        policy->Reset(*ctx.map, mission.num_robots(), mission.num_targets(),
                      mission.seed());
        return policy;
      });
    }
    if (!state->policy->centralized()) {
      ctx.central = nullptr;
    } else if (ctx.central == nullptr) {
      Refuse("aia.builtin_policy", name(),
             "decides from the team's belief, which this policy is not "
             "given: aia.evaluate(..., centralized=True)");
    }
    std::vector<Move> moves(mission.num_robots(), Move::kStay);
    PolicyStatus status;
    {
      ReleaseGil release;
      status = state->policy->Decide(ctx, &moves);
    }
    status_ = status;
    {
      const std::lock_guard<std::mutex> lock(Live().mu);
      PolicyStates::Decided(state.get(), ctx.round);
    }
    py::array_t<long long> out(static_cast<py::ssize_t>(moves.size()));
    auto v = out.mutable_unchecked<1>();
    for (std::size_t i = 0; i < moves.size(); ++i)
      v(static_cast<py::ssize_t>(i)) = static_cast<long long>(moves[i]);
    return out;
  }
  std::string LastStatus() const {
    return std::string(PolicyStatusName(status_));
  }

 private:
  std::shared_ptr<const PolicySpec> spec_;
  PolicyStates states_;  // each mission's own policy
  PolicyStatus status_ = PolicyStatus::kOk;
};

// What one step of VectorMissions did: StepResult's fields as (n,) arrays,
// and `info` (with autoreset: each finished mission's last result).
struct VectorStepResult {
  py::array_t<long long> steps, invalid_moves, localized;
  py::array_t<bool> terminated, truncated, success, done;
  py::dict info;
};

// The process's resident memory and the memory the machine has available
// (MemAvailable), in bytes; -1 where /proc does not say.
long ResidentBytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return -1;
  long size = 0, resident = -1;
  if (std::fscanf(f, "%ld %ld", &size, &resident) != 2) resident = -1;
  std::fclose(f);
  return resident < 0 ? -1 : resident * sysconf(_SC_PAGESIZE);
}

long AvailableBytes() {
  std::FILE* f = std::fopen("/proc/meminfo", "r");
  if (!f) return -1;
  char line[256];
  long kib = -1;
  while (std::fgets(line, sizeof line, f))
    if (std::sscanf(line, "MemAvailable: %ld kB", &kib) == 1) break;
  std::fclose(f);
  return kib < 0 ? -1 : kib * 1024;
}

// A ThreadPool of the process that made it. In a child forked since
// (Python's multiprocessing, os.fork) its threads do not exist: the pool
// is left behind, never joined (its destructor would wait for them for
// ever), and the child makes its own at its first use (as learning/
// parallel.cc does for the policy's pool).
class ProcessPool {
 public:
  explicit ProcessPool(int workers)
      : workers_(workers),
        owner_(::getpid()),
        pool_(std::make_unique<ThreadPool>(workers)) {}
  ~ProcessPool() {
    if (owner_ != ::getpid()) (void)pool_.release();
  }
  ProcessPool(const ProcessPool&) = delete;
  ProcessPool& operator=(const ProcessPool&) = delete;

  ThreadPool& get() {
    if (owner_ != ::getpid()) {
      (void)pool_.release();
      pool_ = std::make_unique<ThreadPool>(workers_);
      owner_ = ::getpid();
    }
    return *pool_;
  }

 private:
  int workers_;
  pid_t owner_;
  std::unique_ptr<ThreadPool> pool_;
};

// n missions of one scenario (seeds given), stepped together on C++
// threads without the GIL; with autoreset, a mission that ends restarts
// with the next seed.
class VectorMissions {
 public:
  // Missions at seeds first .. first + n - 1 (no list of n seeds is made:
  // an n far past memory is refused after two missions, below).
  VectorMissions(const std::string& scenario, std::uint64_t first,
                 std::size_t n, const KeyValues& overrides, int threads,
                 bool autoreset)
      : pool_((threads > 0 ? threads
                           : static_cast<int>(std::max(
                                 1u, std::thread::hardware_concurrency()))) -
              1),
        autoreset_(autoreset) {
    if (n == 0) Refuse("aia.VectorMissions", "n", "must be at least 1");
    // The missions made so far, on average, times those still to make must
    // fit in the memory the machine has available: n past that is refused
    // as soon as it shows (the machine would swap, or the process be
    // killed), not found out by a std::bad_alloc or MuJoCo's "could not
    // allocate" at some mission. Checked after 2, 4, ... 64 missions, then
    // every 64; the average leaves out the first (it also pays for what the
    // process loads once), and until 64 missions, when it is rough, n is
    // refused only at twice what is available.
    long first_bytes = -1;
    try {
      for (std::size_t i = 0; i < n; ++i) {
        missions_.push_back(
            std::make_unique<Mission>(scenario, first + i, overrides));
        missions_.back()->MarkInVector();
        const std::size_t made = i + 1;
        if (made == 1) first_bytes = ResidentBytes();
        if (made < 2 || made == n || first_bytes < 0 ||
            (made < 64 ? (made & (made - 1)) != 0 : made % 64 != 0))
          continue;
        const double each =
            std::max(static_cast<double>(ResidentBytes() - first_bytes), 0.0) /
            static_cast<double>(made - 1);
        const double more = each * static_cast<double>(n - made);
        const long available = AvailableBytes();
        if (available < 0 || more * (made < 64 ? 0.5 : 1.0) <= available)
          continue;
        missions_.clear();
        Refuse("aia.VectorMissions", "n",
               std::to_string(n) + " missions of this scenario need about " +
                   FormatNumber(std::ceil(more / (1 << 20))) + " MiB more (" +
                   FormatNumber(std::ceil(each / 1024.0)) +
                   " KiB each), and this machine has " +
                   FormatNumber(std::floor(available / double(1 << 20))) +
                   " MiB available");
      }
    } catch (const std::bad_alloc&) {
      const std::size_t made = missions_.size();
      missions_.clear();
      Refuse("aia.VectorMissions", "n",
             std::to_string(n) +
                 " missions do not fit in memory (it ran out after " +
                 std::to_string(made) + ")");
    }
    next_seed_ = first + n;  // wraps to 0 after 2^64 - 1, as reset's
  }
  int size() const { return static_cast<int>(missions_.size()); }
  int num_robots() const { return missions_[0]->num_robots(); }
  const char** busy() const { return &busy_; }
  // The vector and each of its missions (missions[i] reach Python) held
  // for one call (CallGuard).
  class Busy {
   public:
    Busy(const VectorMissions& v, const char* where) {
      guards_.push_back(std::make_unique<CallGuard>(v.busy(), where));
      for (const auto& mission : v.missions_)
        guards_.push_back(std::make_unique<CallGuard>(mission->busy(), where));
    }

   private:
    std::vector<std::unique_ptr<CallGuard>> guards_;
  };
  bool autoreset() const { return autoreset_; }
  std::uint64_t next_seed() const { return next_seed_; }
  Mission& at(int i) { return *missions_.at(i); }

  // Every mission restarted at these seeds (one each), on the threads.
  void Reset(const std::vector<std::uint64_t>& seeds) {
    if (static_cast<int>(seeds.size()) != size())
      Refuse("aia.VectorMissions.reset", "seed",
             "one seed per mission: " + std::to_string(size()) + ", got " +
                 std::to_string(seeds.size()));
    {
      ReleaseGil release;
      pool_.get().Run(size(),
                      [&](int i, int) { missions_[i]->Start(seeds[i]); });
    }
    next_seed_ = *std::max_element(seeds.begin(), seeds.end()) + 1;
  }

  // moves: (n, robots). Without autoreset a mission already done ignores
  // its row; with it, a mission that ends at this step restarts with the
  // next seed, its summary and last state in info["final_info"] and
  // info["final_state"] (None for the others; info["_final_info"] the
  // mask), as Gymnasium's vector environments report.
  VectorStepResult Step(py::handle moves) {
    const int n = size(), robots = num_robots();
    const std::vector<Move> flat =
        MovesFrom(moves, {n, robots}, "aia.VectorMissions.step");
    std::vector<std::vector<Move>> next(n);
    for (int i = 0; i < n; ++i)
      next[i].assign(
          flat.begin() + static_cast<std::ptrdiff_t>(i) * robots,
          flat.begin() + static_cast<std::ptrdiff_t>(i + 1) * robots);
    std::vector<long> before(n);
    std::vector<bool> stepped(n);
    for (int i = 0; i < n; ++i) {
      const Episode& e = missions_[i]->episode();
      before[i] = e.invalid_moves();
      stepped[i] = !e.done();
    }
    {
      ReleaseGil release;
      // A failed mission must not keep the others from stepping.
      pool_.get().Run(
          n,
          [&](int i, int) {
            if (stepped[i]) missions_[i]->StepWith(std::move(next[i]));
          },
          OnFailure::kFinish);
    }
    VectorStepResult out;
    out.steps = py::array_t<long long>(n);
    out.invalid_moves = py::array_t<long long>(n);
    out.localized = py::array_t<long long>(n);
    out.terminated = py::array_t<bool>(n);
    out.truncated = py::array_t<bool>(n);
    out.success = py::array_t<bool>(n);
    out.done = py::array_t<bool>(n);
    std::vector<int> finished;
    for (int i = 0; i < n; ++i) {
      const StepResult r = missions_[i]->Result(before[i]);
      out.steps.mutable_at(i) = r.steps;
      out.invalid_moves.mutable_at(i) = r.invalid_moves;
      out.localized.mutable_at(i) = r.localized;
      out.terminated.mutable_at(i) = r.terminated;
      out.truncated.mutable_at(i) = r.truncated;
      out.success.mutable_at(i) = r.success;
      out.done.mutable_at(i) = r.done();
      if (r.done()) finished.push_back(i);
    }
    if (!autoreset_ || finished.empty()) return out;
    std::vector<std::uint64_t> seeds(n);
    {
      const py::object loads = py::module_::import("json").attr("loads");
      py::list final_info, final_state;
      py::array_t<bool> mask(n);
      for (int i = 0; i < n; ++i) {
        final_info.append(py::none());
        final_state.append(py::none());
        mask.mutable_at(i) = false;
      }
      for (int i : finished) {
        final_info[i] = loads(missions_[i]->SummaryText());
        final_state[i] = missions_[i]->State();
        mask.mutable_at(i) = true;
        seeds[i] = next_seed_++;
      }
      out.info["final_info"] = final_info;
      out.info["final_state"] = final_state;
      out.info["_final_info"] = mask;
    }
    Held<VectorStepResult> held(std::move(out));
    {
      ReleaseGil release;
      pool_.get().Run(static_cast<int>(finished.size()), [&](int k, int) {
        missions_[finished[k]]->Start(seeds[finished[k]]);
      });
    }
    return held.Take();
  }

  // Every mission's channels, (n, robots, C, H, W), rendered on the
  // threads (missions of one scenario share a shape; a generator's worlds
  // of other sizes in the global frame are refused).
  py::array_t<float> Channels(const KeyValues& params) {
    const char* where = "aia.VectorMissions.channels";
    const int n = size();
    std::vector<Mission::ChannelJob> jobs;
    jobs.reserve(n);
    for (int i = 0; i < n; ++i) {
      jobs.push_back(missions_[i]->PrepareChannels(params, where));
      if (jobs[i].Shape(num_robots()) != jobs[0].Shape(num_robots()))
        Refuse(where, "frame",
               "the missions' worlds give channels of different sizes "
               "(mission 0 and " +
                   std::to_string(i) +
                   "): use frame centred, or call each mission's channels()");
    }
    std::vector<py::ssize_t> shape = jobs[0].Shape(num_robots());
    const std::size_t each =
        static_cast<std::size_t>(num_robots()) * jobs[0].renderer->ImageSize();
    shape.insert(shape.begin(), n);
    py::array_t<float> out(shape);
    float* data = out.mutable_data();
    Held<py::array_t<float>> held(std::move(out));
    {
      ReleaseGil release;
      pool_.get().Run(n, [&](int i, int) {
        missions_[i]->RenderChannels(jobs[i], data + i * each);
      });
    }
    return held.Take();
  }

 private:
  ProcessPool pool_;  // the caller is the first of `threads`
  bool autoreset_;
  std::uint64_t next_seed_ = 0;
  std::vector<std::unique_ptr<Mission>> missions_;
  mutable const char* busy_ = nullptr;  // Busy
};

class PyDataset {
 public:
  PyDataset(const std::vector<std::string>& paths, const KeyValues& params) {
    channels_ = ChannelSettings(params, "aia.Dataset");
    try {
      data_ = ReadDataset(paths, "paths");
    } catch (const InputError& e) {
      // "command line" is not Python's; a file's error names the callable
      // first, as every other Python error does.
      if (e.file() != "command line" && e.key() == "paths")
        Refuse("aia.Dataset", "paths", "'" + e.file() + "': " + e.message());
      throw Renamed(e, "aia.Dataset");
    }
    if (data_.samples.empty())
      Refuse("aia.Dataset", "paths", "holds no samples");
    const std::vector<std::vector<int>> of_world = SamplesByWorld(data_);
    valid_.resize(data_.samples.size());
    for (std::size_t wi = 0; wi < data_.worlds.size(); ++wi) {
      const DatasetWorld& w = data_.worlds[wi];
      // As aia train renders them: one pixel per lattice step.
      const ChannelParams at_step = AtLatticeStep(channels_, w.lattice_step);
      if (const std::string why = ChannelGridProblem(w.size, at_step);
          !why.empty())
        Refuse("aia.Dataset", "channels",
               "world of episode " + std::to_string(w.episode) + ": " + why);
      const Map map(w.size, w.obstacles, w.map_cell, w.lattice_step,
                    w.robot_radius);
      renderers_.emplace_back(map.occupancy(), w.size, at_step, &map.lattice());
      for (int i : of_world[wi])
        valid_[i] = ValidMoveBits(map.lattice(), data_.samples[i].position);
    }
  }

  int size() const { return static_cast<int>(data_.samples.size()); }
  const char** busy() const { return &busy_; }
  int num_worlds() const { return static_cast<int>(data_.worlds.size()); }

  // Per sample: label, useful, acted, world index, episode, step, robot,
  // and the valid moves (n, 4; ValidMoveBits).
  py::dict Samples() const {
    const py::ssize_t n = size();
    py::array_t<long long> label(n), acted(n), world(n), episode(n), step(n),
        robot(n);
    py::array_t<bool> useful(n);
    py::array_t<bool> valid({n, static_cast<py::ssize_t>(kNumMoves)});
    for (py::ssize_t i = 0; i < n; ++i) {
      const DatasetSample& s = data_.samples[i];
      for (int m = 0; m < kNumMoves; ++m)
        valid.mutable_at(i, m) = (valid_[i] >> m) & 1u;
      label.mutable_at(i) = static_cast<long long>(s.label);
      acted.mutable_at(i) = static_cast<long long>(s.acted);
      world.mutable_at(i) = s.world;
      episode.mutable_at(i) = s.episode;
      step.mutable_at(i) = s.step;
      robot.mutable_at(i) = s.robot;
      useful.mutable_at(i) = s.useful;
    }
    py::dict d;
    d["label"] = label;
    d["useful"] = useful;
    d["acted"] = acted;
    d["world"] = world;
    d["episode"] = episode;
    d["step"] = step;
    d["robot"] = robot;
    d["valid"] = valid;
    return d;
  }

  // Whether each world is held out for validation, as `aia train` splits
  // (--val-share, --seed).
  py::array_t<bool> ValidationWorlds(py::handle share_arg,
                                     py::handle seed_arg) const {
    // A real number: not a bool, a complex, an array, nor one past a
    // double (10**400).
    const auto refuse = [&] {
      Refuse("aia.Dataset.split", "val_share",
             "must be a number in [0, 1], got " + Shown(share_arg));
    };
    if (IsBool(share_arg) || !PyNumber_Check(share_arg.ptr()) ||
        PyComplex_Check(share_arg.ptr()) ||
        py::isinstance<py::array>(share_arg))
      refuse();
    double share = 0.0;
    try {
      share = py::float_(py::reinterpret_borrow<py::object>(share_arg));
    } catch (const py::error_already_set&) {
      refuse();
    }
    if (!(share >= 0.0 && share <= 1.0))
      Refuse("aia.Dataset.split", "val_share",
             "must be a number in [0, 1], got " + Shown(share_arg));
    const std::uint64_t seed =
        *SeedArg(seed_arg, "aia.Dataset.split", "seed", false);
    py::array_t<bool> out(num_worlds());
    for (int w = 0; w < num_worlds(); ++w) {
      Rng rng(seed, "train/split",
              static_cast<std::uint64_t>(data_.worlds[w].seed));
      out.mutable_at(w) = rng.Uniform() < share;
    }
    return out;
  }

  // (B, C, H, W) float32 images of these samples and their labels.
  py::tuple Batch(py::handle indices_arg) {
    const std::vector<long long> indices = Integers(
        indices_arg, {-1}, 0, size() - 1, "aia.Dataset.batch", "indices",
        "a sample index in [0, " + std::to_string(size() - 1) + "]",
        "sample indices");
    if (indices.empty())
      Refuse("aia.Dataset.batch", "indices", "no sample indices");
    const ChannelRenderer& first = renderers_[data_.samples[indices[0]].world];
    for (long long i : indices) {
      const ChannelRenderer& r = renderers_[data_.samples[i].world];
      if (r.height() != first.height() || r.width() != first.width())
        Refuse("aia.Dataset.batch", "indices",
               "worlds of different sizes in the global frame; use the "
               "centred frame or one workspace size");
    }
    const py::ssize_t b = static_cast<py::ssize_t>(indices.size());
    py::array_t<float> images({b, static_cast<py::ssize_t>(first.channels()),
                               static_cast<py::ssize_t>(first.height()),
                               static_cast<py::ssize_t>(first.width())});
    py::array_t<long long> labels(b);
    float* data = images.mutable_data();
    const std::size_t size = first.ImageSize();
    for (py::ssize_t k = 0; k < b; ++k)
      labels.mutable_at(k) =
          static_cast<long long>(data_.samples[indices[k]].label);
    Held<py::tuple> held(py::make_tuple(std::move(images), std::move(labels)));
    {
      ReleaseGil release;
      for (py::ssize_t k = 0; k < b; ++k) {
        const DatasetSample& s = data_.samples[indices[k]];
        const DatasetWorld& w = data_.worlds[s.world];
        renderers_[s.world].Render(s.position, s.neighbours, s.targets,
                                   w.log_det_prior, w.eps, data + k * size,
                                   SampleMemory(s, w));
      }
    }
    return held.Take();
  }

 private:
  ChannelParams channels_;
  Dataset data_;
  std::vector<ChannelRenderer> renderers_;
  std::vector<std::uint8_t> valid_;     // per sample, ValidMoveBits
  mutable const char* busy_ = nullptr;  // CallGuard (batch renders without
                                        // the GIL)
};

// How far aia.evaluate is: the Python policy's runs finished (each ends
// when its policy is destroyed), reported to a Python callable from the
// next decision, which holds the GIL anyway (no thread of its own).
struct EvalProgress {
  py::object callback;  // None: no report
  int done_before = 0;  // runs of this policy already in `out`
  int total = 0;        // runs of this policy in the evaluation
  std::atomic<int> finished{0};
  int reported = 0;
  void Start() {  // GIL held: the runs done before
    if (!callback.is_none()) callback(std::min(done_before, total), total);
  }
  void Report() {  // GIL held
    const int now = finished.load();
    if (callback.is_none() || now == reported) return;
    reported = now;
    callback(std::min(done_before + now, total), total);
  }
};

// While one lives, what runs on this thread (a progress callback, a
// policy) is inside an evaluation: an aia.evaluate it calls is refused (it
// would wait for this one's turn for ever).
struct InsideEvaluate {
  InsideEvaluate() { t_inside_evaluate = true; }
  ~InsideEvaluate() { t_inside_evaluate = false; }
  InsideEvaluate(const InsideEvaluate&) = delete;
  InsideEvaluate& operator=(const InsideEvaluate&) = delete;
};

// A Python callable as a policy of aia's own loop (evaluate): each decision
// takes the GIL, hands the callable a view of the decision and reads its
// moves. A Python exception ends the evaluation and reaches the caller.
class CallbackPolicy : public Policy {
 public:
  CallbackPolicy(std::string name, bool centralized, py::object decide,
                 std::shared_ptr<EvalProgress> progress)
      : name_(std::move(name)),
        centralized_(centralized),
        decide_(std::move(decide)),
        progress_(std::move(progress)) {}
  ~CallbackPolicy() override {
    if (started_) ++progress_->finished;
    MissionEnded(id_);
    AcquireGil gil;
    decide_ = py::object();
  }
  std::string_view name() const override { return name_; }
  bool centralized() const override { return centralized_; }
  void Reset(const Map&, int, int, std::uint64_t seed) override {
    seed_ = seed;
    MissionEnded(id_);
    id_ = g_next_mission_id++;
    started_ = true;
  }
  PolicyStatus Decide(const DecisionContext& ctx,
                      std::vector<Move>* moves) override {
    AcquireGil gil;
    const InsideEvaluate inside;  // the progress callback and the policy
    progress_->Report();
    const int n = static_cast<int>(moves->size());
    py::object view = py::cast(new Mission(&ctx, seed_, id_, 0),
                               py::return_value_policy::take_ownership);
    struct Invalidate {
      py::object& view;
      ~Invalidate() { view.cast<Mission&>().Invalidate(); }
    } invalidate{view};
    const py::object result = decide_(view);
    *moves = MovesFrom(result, {n}, "aia.evaluate", "policy's moves");
    return PolicyStatus::kOk;
  }

 private:
  std::string name_;
  bool centralized_;
  py::object decide_;
  std::shared_ptr<EvalProgress> progress_;
  std::uint64_t seed_ = 0, id_ = 0;
  bool started_ = false;
};

class CallbackSpec : public PolicySpec {
 public:
  CallbackSpec(const std::string& name, bool centralized, py::object decide,
               std::shared_ptr<EvalProgress> progress)
      : PolicySpec(name, centralized),
        decide_(std::move(decide)),
        progress_(std::move(progress)) {}
  ~CallbackSpec() override {
    AcquireGil gil;
    decide_ = py::object();
  }
  std::unique_ptr<Policy> Create() const override {
    AcquireGil gil;
    return std::make_unique<CallbackPolicy>(name(), centralized(), decide_,
                                            progress_);
  }
  // effective.yaml's line: rows under this name are resumed whatever the
  // code does, so a changed policy needs another name.
  ConfigNode Params() const override {
    ConfigNode node = ConfigNode::Map();
    node.Set("kind", ConfigNode::Scalar("python"));
    node.Set("centralized",
             ConfigNode::Scalar(centralized() ? "true" : "false"));
    return node;
  }

 private:
  py::object decide_;
  std::shared_ptr<EvalProgress> progress_;
};

// The C library's stdout and stderr (what `aia eval` prints: its header,
// summary table and notes) caught in memory while one lives, so that
// aia.evaluate writes nothing itself; Python's own sys.stdout and
// sys.stderr write to the file descriptors and are untouched.
class CStdioCapture {
 public:
  CStdioCapture() : out_(stdout), err_file_saved_(stderr) {
    std::fflush(stdout);
    std::fflush(stderr);
    out_file_ = open_memstream(&out_text_, &out_size_);
    err_file_ = open_memstream(&err_text_, &err_size_);
    if (out_file_) stdout = out_file_;
    if (err_file_) stderr = err_file_;
  }
  ~CStdioCapture() { Finish(); }
  CStdioCapture(const CStdioCapture&) = delete;
  CStdioCapture& operator=(const CStdioCapture&) = delete;

  // Restores stdout and stderr; returns what was written to stderr.
  std::string Finish() {
    if (done_) return err_;
    done_ = true;
    stdout = out_;
    stderr = err_file_saved_;
    if (out_file_) std::fclose(out_file_);
    if (err_file_) std::fclose(err_file_);
    if (err_text_) err_.assign(err_text_, err_size_);
    std::free(out_text_);
    std::free(err_text_);
    return err_;
  }

 private:
  FILE* out_;
  FILE* err_file_saved_;
  FILE* out_file_ = nullptr;
  FILE* err_file_ = nullptr;
  char* out_text_ = nullptr;
  char* err_text_ = nullptr;
  std::size_t out_size_ = 0, err_size_ = 0;
  bool done_ = false;
  std::string err_;
};

// aia.evaluate's core: `aia eval` with one more policy, the callable.
// Returns the exit code and what aia eval wrote to stderr (notes such as
// dropped rows; the wrapper turns them into Python warnings).
// (The callables as handles: a thread that finalization ends at the GIL
// below unwinds through no Python reference of its own; see Held.)
py::tuple Evaluate(py::handle decide, const std::string& name, bool centralized,
                   const std::vector<std::string>& sizes, int seeds,
                   std::uint64_t seed_base, const std::string& out, int threads,
                   const std::vector<std::string>& sets, py::handle progress,
                   int done_before, int total) {
  if (t_inside_evaluate)
    Refuse("aia.evaluate", "",
           "called from a policy or progress callback of a running "
           "aia.evaluate: evaluations do not nest (it would wait for the "
           "running one for ever); run it after");
  EvalOptions o;
  o.sizes.clear();
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    std::string why;
    const std::optional<TeamSize> size = TeamSize::FromText(sizes[i], &why);
    if (!size)
      Refuse("aia.evaluate", "sizes[" + std::to_string(i) + "]",
             (why.empty() ? "must be " + std::string(TeamSize::kExpect) : why) +
                 ", got '" + sizes[i] + "'");
    o.sizes.push_back(*size);
  }
  o.seeds = seeds;
  o.seed_base = seed_base;
  o.out_dir = out;
  o.threads = threads;
  o.sets = sets;
  o.progress = false;  // aia eval's own line would bypass sys.stderr
  o.exit_on_interrupt = false;
  auto report = std::make_shared<EvalProgress>();
  report->callback = py::reinterpret_borrow<py::object>(progress);
  report->done_before = done_before;
  report->total = total;
  o.started = [report] {
    AcquireGil gil;
    const InsideEvaluate inside;
    report->Start();
  };
  o.extra_policies = {std::make_shared<CallbackSpec>(
      name, centralized, py::reinterpret_borrow<py::object>(decide), report)};
  report.reset();  // held by the options only
  Held<EvalOptions> options(std::move(o));
  int rc = 0;
  std::string notes;
  {
    ReleaseGil release;
    // Calls from several threads take turns: the capture of C stdio and the
    // Ctrl-C handler are the process's (two at once crashed in fflush and
    // printed eval's lines). Taken without the GIL, which the running call
    // needs for its policy's callbacks.
    static std::mutex one_at_a_time;
    const std::lock_guard<std::mutex> turn(one_at_a_time);
    CStdioCapture quiet;
    InterruptScope scope;  // Ctrl-C: the rows done are written; back to Python
    struct Running {       // after the scope, which clears the flag
      Running() { ++g_evaluations; }
      ~Running() { --g_evaluations; }
    } running;
    try {
      rc = RunEval(options.get());
    } catch (const InputError& e) {
      throw Renamed(e, "aia.evaluate");
    }
    notes = quiet.Finish();
  }
  return py::make_tuple(rc, notes);
}

// ---------------------------------------------------------------------------
// The bindings, one function per area.

void BindErrors(py::module_& m) {
  static py::exception<InputError> input_error(m, "InputError",
                                               PyExc_ValueError);
  input_error.doc() =
      "Bad input: a scenario, an override, a model file or an argument "
      "given from Python. A ValueError; its text is one line, "
      "'WHERE: KEY: what is wrong' (WHERE a file and line, or the Python "
      "callable).";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      // A scenario's bytes need not be UTF-8: shown escaped, not lost.
      const std::string text = e.Format();
      PyObject* message = PyUnicode_DecodeUTF8(
          text.data(), static_cast<Py_ssize_t>(text.size()),
          "backslashreplace");
      PyErr_SetObject(input_error.ptr(), message);
      Py_XDECREF(message);
    }
  });
}

void BindMoves(py::module_& m) {
  py::enum_<Move> move(m, "Move", py::arithmetic(),
                       "A robot's move on the lattice; equal to its int "
                       "(Move.UP == 2).");
  move.value("LEFT", Move::kLeft, "0: -x")
      .value("RIGHT", Move::kRight, "1: +x")
      .value("UP", Move::kUp, "2: +y")
      .value("DOWN", Move::kDown, "3: -y")
      .value("STAY", Move::kStay,
             "4: the robot keeps its lattice point (a valid decision)");
  // Equal to its int and hashed as it (pybind11 compares an enum class
  // only with its own type), so that Move.UP == 2 and {2: x}[Move.UP]:
  // these replace pybind11's own, not overload them.
  const auto equal = [](Move a, py::handle b) {
    const py::object i = AsInteger(b);
    return i && i.equal(py::int_(static_cast<int>(a)));
  };
  move.attr("__eq__") =
      py::cpp_function(equal, py::name("__eq__"), py::is_method(move));
  move.attr("__ne__") =
      py::cpp_function([equal](Move a, py::handle b) { return !equal(a, b); },
                       py::name("__ne__"), py::is_method(move));
  move.attr("__hash__") =
      py::cpp_function([](Move a) { return static_cast<int>(a); },
                       py::name("__hash__"), py::is_method(move));
}

void BindMission(py::module_& m) {
  py::class_<StepResult>(m, "StepResult",
                         "What one Mission.step did, as Gymnasium tells it.")
      .def_readonly("steps", &StepResult::steps,
                    "decision steps taken so far (Mission.steps)")
      .def_readonly("invalid_moves", &StepResult::invalid_moves,
                    "moves the world rule replaced at this step")
      .def_readonly("localized", &StepResult::localized,
                    "targets below eps in the team's best estimate")
      .def_readonly("terminated", &StepResult::terminated,
                    "the mission reached an end state: success, or no "
                    "robot left")
      .def_readonly("truncated", &StepResult::truncated,
                    "the mission was cut short: mission.max_steps")
      .def_readonly("success", &StepResult::success,
                    "every target localized (summary.json's success)")
      .def_property_readonly("done", &StepResult::done,
                             "terminated or truncated")
      .def("__repr__",
           [](const StepResult& r) {
             return "StepResult(steps=" + std::to_string(r.steps) +
                    ", invalid_moves=" + std::to_string(r.invalid_moves) +
                    ", localized=" + std::to_string(r.localized) +
                    ", terminated=" + (r.terminated ? "True" : "False") +
                    ", truncated=" + (r.truncated ? "True" : "False") +
                    ", success=" + (r.success ? "True" : "False") + ")";
           })
      // Pickled as its fields (a worker process sends its results back).
      .def(py::pickle(
          [](const StepResult& r) {
            return py::make_tuple(r.steps, r.invalid_moves, r.localized,
                                  r.terminated, r.truncated, r.success);
          },
          [](const py::tuple& t) {
            if (t.size() != 6)
              Refuse("aia.StepResult", "state",
                     "must be its 6 fields, got " + Shown(t));
            StepResult r;
            r.steps = t[0].cast<int>();
            r.invalid_moves = t[1].cast<long>();
            r.localized = t[2].cast<int>();
            r.terminated = t[3].cast<bool>();
            r.truncated = t[4].cast<bool>();
            r.success = t[5].cast<bool>();
            return r;
          }));

  py::class_<Mission>(m, "Mission",
                      "One mission of a scenario file, stepped from Python "
                      "(aia.Mission wraps it).")
      .def(py::init([](const std::string& scenario, py::handle seed,
                       const KeyValues& overrides, const std::string& where) {
             const std::optional<std::uint64_t> s =
                 SeedArg(seed, where, "seed", true);
             try {
               return std::make_unique<Mission>(scenario, s, overrides);
             } catch (const InputError& e) {
               throw Renamed(e, where);
             }
           }),
           py::arg("scenario"), py::arg("seed") = py::none(),
           py::arg("overrides") = KeyValues{}, py::arg("where") = "aia.Mission",
           "`where` names the callable in errors (the env that made it).")
      .def(
          "_restart",
          [](Mission& m, py::handle seed, const std::string& where) {
            if (!m.owned() || m.in_vector())
              Refuse(where, "",
                     "only a Mission made alone can be restarted (not a "
                     "decision's view, nor one of an aia.VectorMissions)");
            const std::optional<std::uint64_t> s =
                SeedArg(seed, where, "seed", false);
            const CallGuard guard(m.busy(), where.c_str());
            try {
              m.Start(s);
            } catch (const InputError& e) {
              throw Renamed(e, where);
            }
          },
          py::arg("seed"), py::arg("where"),
          "The mission again from step 0 at `seed`, from the scenario as "
          "it was read when the mission was made (what the envs' reset "
          "does).")
      .def("state", OneCall(&Mission::State, "aia.Mission.state"),
           "What the robots know now (numpy arrays), the truth apart.")
      .def("step", OneCall(&Mission::Step, "aia.Mission.step"),
           py::arg("moves"),
           "One decision step: one integer move 0..4 per robot.")
      .def("valid_moves",
           OneCall(&Mission::ValidMoves, "aia.Mission.valid_moves"),
           "(N, 4) bool: the moves that stay on the lattice.")
      .def("render", OneCall(&Mission::Render, "aia.Mission.render"),
           py::arg("width") = 640, py::arg("height") = 480,
           "An RGB frame (H, W, 3) uint8 with aia render's overlays.")
      .def("channels", OneCall(&Mission::Channels, "aia.Mission.channels"),
           py::arg("params") = KeyValues{},
           "I-GBNet's input of every robot, (N, C, H, W) float32.")
      .def("summary_json",
           OneCall(&Mission::SummaryText, "aia.Mission.summary"),
           "summary.json's text.")
      .def("diagnostics_json",
           OneCall(&Mission::DiagnosticsText, "aia.Mission.diagnostics"),
           "diagnostics.json's text.")
      .def_property_readonly(
          "num_robots", OneCall(&Mission::num_robots, "aia.Mission.num_robots"))
      .def_property_readonly("num_targets", OneCall(&Mission::num_targets,
                                                    "aia.Mission.num_targets"))
      .def_property_readonly("steps",
                             OneCall(&Mission::step, "aia.Mission.steps"),
                             "decision steps taken")
      .def_property_readonly("done",
                             OneCall(&Mission::done, "aia.Mission.done"))
      .def_property_readonly("success",
                             OneCall(&Mission::success, "aia.Mission.success"))
      .def_property_readonly(
          "flowtime", OneCall(&Mission::flowtime, "aia.Mission.flowtime"),
          "steps to success; -1 until then")
      .def_property_readonly(
          "max_steps", OneCall(&Mission::max_steps, "aia.Mission.max_steps"))
      .def_property_readonly(
          "asynchronous",
          OneCall(&Mission::asynchronous, "aia.Mission.asynchronous"),
          "mission.decisions is async")
      .def_property_readonly(
          "ready", OneCall(&Mission::Ready, "aia.Mission.ready"),
          "(N,) bool: the robots whose moves the next step uses (all in "
          "lockstep; with mission.decisions async, those whose move has "
          "ended)")
      .def_property_readonly("seed",
                             OneCall(&Mission::seed, "aia.Mission.seed"))
      .def_property_readonly(
          "scenario_warnings",
          OneCall(&Mission::scenario_warnings, "aia.Mission.scenario_warnings"),
          "the scenario's warnings, 'FILE:LINE: key: what' (keys given a "
          "value that changes nothing where they stand)")
      .def_property_readonly("owned",
                             OneCall(&Mission::owned, "aia.Mission.owned"),
                             "False for a view inside aia.evaluate");
}

void BindVectorMissions(py::module_& m) {
  py::class_<VectorStepResult>(
      m, "VectorStepResult",
      "What one VectorMissions.step did: StepResult's fields as (n,) "
      "arrays, and info.")
      .def_readonly("steps", &VectorStepResult::steps)
      .def_readonly("invalid_moves", &VectorStepResult::invalid_moves)
      .def_readonly("localized", &VectorStepResult::localized)
      .def_readonly("terminated", &VectorStepResult::terminated)
      .def_readonly("truncated", &VectorStepResult::truncated)
      .def_readonly("success", &VectorStepResult::success)
      .def_readonly("done", &VectorStepResult::done)
      .def_readonly("info", &VectorStepResult::info,
                    "with autoreset: final_info (summary dicts), "
                    "final_state (state dicts), _final_info (mask)")
      .def(py::pickle(
          [](const VectorStepResult& r) {
            return py::make_tuple(r.steps, r.invalid_moves, r.localized,
                                  r.terminated, r.truncated, r.success, r.done,
                                  r.info);
          },
          [](const py::tuple& t) {
            if (t.size() != 8)
              Refuse("aia.VectorStepResult", "state",
                     "must be its 8 fields, got " + Shown(t));
            VectorStepResult r;
            r.steps = t[0].cast<py::array_t<long long>>();
            r.invalid_moves = t[1].cast<py::array_t<long long>>();
            r.localized = t[2].cast<py::array_t<long long>>();
            r.terminated = t[3].cast<py::array_t<bool>>();
            r.truncated = t[4].cast<py::array_t<bool>>();
            r.success = t[5].cast<py::array_t<bool>>();
            r.done = t[6].cast<py::array_t<bool>>();
            r.info = t[7].cast<py::dict>();
            return r;
          }));

  py::class_<VectorMissions>(
      m, "VectorMissions",
      "Missions of one scenario stepped together on C++ threads.")
      .def(py::init([](const std::string& scenario, py::handle seed,
                       std::size_t n, const KeyValues& overrides,
                       py::handle threads, bool autoreset) {
             const int t = static_cast<int>(
                 IntegerArg(threads, "aia.VectorMissions", "threads", 0, 4096));
             const std::uint64_t first =
                 *SeedArg(seed, "aia.VectorMissions", "seed", false);
             if (n == 0)
               Refuse("aia.VectorMissions", "n", "must be at least 1");
             if (n - 1 > std::numeric_limits<std::uint64_t>::max() - first)
               Refuse("aia.VectorMissions", "seed",
                      "seed + n - 1 passes 2^64 - 1");
             try {
               return std::make_unique<VectorMissions>(scenario, first, n,
                                                       overrides, t, autoreset);
             } catch (const InputError& e) {
               throw Renamed(e, "aia.VectorMissions");
             }
           }),
           py::arg("scenario"), py::arg("seed"), py::arg("n"),
           py::arg("overrides") = KeyValues{}, py::arg("threads") = 0,
           py::arg("autoreset") = false)
      .def("__len__", &VectorMissions::size)
      .def("mission", &VectorMissions::at,
           py::return_value_policy::reference_internal,
           "The i-th mission (the same object across autoresets).")
      .def(
          "reset",
          [](VectorMissions& v, py::handle seeds) {
            std::vector<std::uint64_t> s;
            for (py::handle seed : seeds)
              s.push_back(
                  *SeedArg(seed, "aia.VectorMissions.reset", "seed", false));
            const VectorMissions::Busy busy(v, "aia.VectorMissions.reset");
            v.Reset(s);
          },
          py::arg("seeds"), "Every mission restarted, one seed each.")
      .def(
          "step",
          [](VectorMissions& v, py::handle moves) {
            const VectorMissions::Busy busy(v, "aia.VectorMissions.step");
            return v.Step(moves);
          },
          py::arg("moves"),
          "One step of every mission: (n, robots) integer moves 0..4.")
      .def(
          "channels",
          [](VectorMissions& v, const KeyValues& params) {
            const VectorMissions::Busy busy(v, "aia.VectorMissions.channels");
            return v.Channels(params);
          },
          py::arg("params"),
          "Every mission's Mission.channels(), (n, robots, C, H, W), "
          "rendered on the threads.")
      .def_property_readonly(
          "num_robots",
          OneCall(&VectorMissions::num_robots, "aia.VectorMissions.num_robots"))
      .def_property_readonly("autoreset", &VectorMissions::autoreset)
      .def_property_readonly("next_seed", &VectorMissions::next_seed,
                             "the seed the next restart takes");
}

void BindDataset(py::module_& m) {
  py::class_<PyDataset>(m, "Dataset",
                        "The samples of aia dataset shards, rendered by the "
                        "C++ renderer.")
      .def(py::init<const std::vector<std::string>&, const KeyValues&>(),
           py::arg("paths"), py::arg("params") = KeyValues{})
      .def("__len__", &PyDataset::size)
      .def_property_readonly("num_worlds", &PyDataset::num_worlds)
      .def("samples", &PyDataset::Samples,
           "Per sample: label, useful, acted, world, episode, step, robot, "
           "valid (the moves that stay on the lattice).")
      .def("validation_worlds", &PyDataset::ValidationWorlds, py::arg("share"),
           py::arg("seed"),
           "Whether each world is held out, as aia train splits.")
      .def("batch", OneCall(&PyDataset::Batch, "aia.Dataset.batch"),
           py::arg("indices"),
           "(images (B, C, H, W) float32, labels (B,) int64).");
}

void BindPolicies(py::module_& m) {
  py::class_<BuiltinPolicy>(m, "BuiltinPolicy",
                            "A registered policy deciding on a mission.")
      .def(py::init<const std::string&, const KeyValues&>(), py::arg("name"),
           py::arg("params") = KeyValues{})
      .def("decide", &BuiltinPolicy::Decide, py::arg("mission"),
           "One move per robot (int64) from what the robots know.")
      .def_property_readonly("name", &BuiltinPolicy::name)
      .def_property_readonly("centralized", &BuiltinPolicy::centralized)
      .def_property_readonly("last_status", &BuiltinPolicy::LastStatus);
  m.def(
      "policy_names", [] { return AllPolicies().Names(); },
      "The registered policies' names.");
}

void BindEvaluate(py::module_& m) {
  m.def("evaluate", &Evaluate, py::arg("decide"), py::arg("name"),
        py::arg("centralized"), py::arg("sizes"), py::arg("seeds"),
        py::arg("seed_base"), py::arg("out"), py::arg("threads"),
        py::arg("sets"), py::arg("progress"), py::arg("done_before"),
        py::arg("total"),
        "aia eval with the callable as one more policy; returns (exit "
        "code, what aia eval wrote to stderr).");
}

void BindInstallation(py::module_& m) {
  m.def(
      "_use_installed",
      [](const std::string& lib_dir, const std::string& data_dir) {
        SetInstalledDirs(lib_dir, data_dir);
      },
      py::arg("lib_dir"), py::arg("data_dir"),
      "An installed package's own plugins and data (its _install.py).");
  m.def(
      "_installed_dirs",
      [] { return py::make_tuple(InstalledLibDir(), InstalledDataDir()); },
      "(plugin folder, data folder) of an installed aia, '' in a build.");
  m.def(
      "_default_model_path",
      [](const std::string& coordination) {
        if (coordination != "rules" && coordination != "none")
          throw py::value_error("coordination: 'rules' or 'none', not '" +
                                coordination + "'");
        return DefaultModelPath(coordination == "none" ? Coordination::kNone
                                                       : Coordination::kRules);
      },
      py::arg("coordination") = "rules",
      "Where policy.model points when a scenario does not say, for "
      "policy.coordination 'rules' or 'none'.");
}

}  // namespace
}  // namespace python
}  // namespace aia

PYBIND11_MODULE(_aia, m) {
  m.doc() = "aia's C++ core (use the aia package)";
  // numpy's C API is set up once, here: done first on a worker thread it
  // would import numpy under a static's guard while another thread holds
  // the GIL and waits on that guard.
  py::module_::import("numpy");
  (void)py::array_t<long long>(1);
  py::module_::import("atexit").attr("register")(
      py::cpp_function(&aia::python::StopEvaluationsAtExit));
  m.attr("MAX_EVAL_WORLDS") = aia::kMaxEvalWorlds;
  m.def(
      "_exiting", [] { return aia::python::g_exiting.load(); },
      "whether the interpreter's exit has begun (aia.evaluate's end then)");
  aia::python::BindErrors(m);
  aia::python::BindMoves(m);
  aia::python::BindMission(m);
  aia::python::BindVectorMissions(m);
  aia::python::BindDataset(m);
  aia::python::BindPolicies(m);
  aia::python::BindEvaluate(m);
  aia::python::BindInstallation(m);
}
