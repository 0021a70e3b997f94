// aia._aia: the C++ core of the Python package (python/aia/__init__.py
// wraps it; docs/python.md). A Mission is one episode of the same loop as
// `aia run` (runtime/episode.h) whose moves come from Python; a builtin
// policy is a registered policy deciding on a mission's state with the
// same truth fence as in the loop.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "aia/core/error.h"
#include "aia/planning/policy.h"
#include "aia/planning/registry.h"
#include "aia/runtime/episode.h"
#include "aia/runtime/generated.h"
#include "aia/runtime/instance.h"
#include "aia/runtime/mission.h"
#include "aia/runtime/observers.h"
#include "aia/runtime/policies.h"
#include "aia/scenario/loader.h"

namespace py = pybind11;

namespace aia {
namespace python {
namespace {

// (key path, YAML text) pairs, as Python's wrapper passes `overrides`.
using KeyValues = std::vector<std::pair<std::string, std::string>>;

std::vector<Override> AsOverrides(const KeyValues& pairs,
                                  const std::string& flag_prefix) {
  std::vector<Override> out;
  for (const auto& [key, value] : pairs)
    out.push_back({flag_prefix + key, key, value});
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

// Moves from Python: one per robot, each 0 (left), 1 (right), 2 (up),
// 3 (down) or 4 (stay).
std::vector<Move> MovesFrom(const py::array_t<long long>& moves, int n) {
  const py::buffer_info b = moves.request();
  if (b.ndim != 1 || b.shape[0] != n)
    throw py::value_error(
        "moves: must be one move per robot (" + std::to_string(n) +
        "), got shape " +
        py::str(py::tuple(py::cast(b.shape))).cast<std::string>());
  std::vector<Move> out(n);
  const auto view = moves.unchecked<1>();
  for (int i = 0; i < n; ++i) {
    const long long m = view(i);
    if (m < 0 || m > 4)
      throw py::value_error("moves[" + std::to_string(i) +
                            "]: must be 0 (left), 1 (right), 2 (up), 3 (down) "
                            "or 4 (stay), got " +
                            std::to_string(m));
    out[i] = static_cast<Move>(m);
  }
  return out;
}

template <typename T>
py::array_t<T> Array(std::vector<py::ssize_t> shape) {
  return py::array_t<T>(shape);
}

std::atomic<std::uint64_t> g_next_mission_id{1};

class Mission {
 public:
  Mission(const std::string& scenario, std::optional<std::uint64_t> seed,
          const KeyValues& overrides)
      : id_(g_next_mission_id++) {
    std::vector<Override> all;
    if (seed) all.push_back({"seed", "seed", std::to_string(*seed)});
    for (const Override& o : AsOverrides(overrides, "overrides: "))
      all.push_back(o);
    instance_ = BuildInstance(LoadScenario(scenario, all));
    auto policy = std::make_unique<ExternalPolicy>();
    external_ = policy.get();
    episode_ = std::make_unique<Episode>(instance_, std::move(policy));
    episode_->AddObserver(&moves_);
    episode_->AddObserver(&estimate_);
    moves_.OnStart(*episode_);
    estimate_.OnStart(*episode_);
  }

  std::uint64_t id() const { return id_; }
  const Episode& episode() const { return *episode_; }
  int num_robots() const { return episode_->world().NumRobots(); }
  int num_targets() const { return episode_->world().NumTargets(); }

  py::dict State() const {
    const Episode& e = *episode_;
    const int n = num_robots(), m = num_targets();
    const Lattice& lattice = e.world().map.lattice();
    auto positions = Array<double>({n, 2});
    auto lattice_index = Array<long long>({n});
    auto cells = Array<long long>({n, 2});
    auto active = Array<bool>({n});
    auto neighbors = Array<bool>({n, n});
    auto mean = Array<double>({n, m, 2});
    auto cov = Array<double>({n, m, 2, 2});
    auto det = Array<double>({n, m});
    auto p = positions.mutable_unchecked<2>();
    auto li = lattice_index.mutable_unchecked<1>();
    auto c = cells.mutable_unchecked<2>();
    auto a = active.mutable_unchecked<1>();
    auto g = neighbors.mutable_unchecked<2>();
    auto mu = mean.mutable_unchecked<3>();
    auto sigma = cov.mutable_unchecked<4>();
    auto d = det.mutable_unchecked<2>();
    const BeliefSet& beliefs = e.beliefs();
    for (int i = 0; i < n; ++i) {
      p(i, 0) = e.robot_positions()[i].x();
      p(i, 1) = e.robot_positions()[i].y();
      const int q = e.robot_lattice()[i];
      li(i) = q;
      c(i, 0) = lattice.Ix(q);
      c(i, 1) = lattice.Iy(q);
      a(i) = e.comm().Active(i);
      for (int j = 0; j < n; ++j) g(i, j) = false;
      for (int j : e.comm().Neighbors(i)) g(i, j) = true;
      for (int k = 0; k < m; ++k) {
        const Vec2 x = beliefs.PositionMean(i, k);
        const Mat2 s = beliefs.PositionCovariance(i, k);
        mu(i, k, 0) = x.x();
        mu(i, k, 1) = x.y();
        for (int r = 0; r < 2; ++r)
          for (int col = 0; col < 2; ++col) sigma(i, k, r, col) = s(r, col);
        d(i, k) = e.Det(i, k);
      }
    }
    auto truth_positions = Array<double>({m, 2});
    auto t = truth_positions.mutable_unchecked<2>();
    for (int k = 0; k < m; ++k) {
      t(k, 0) = e.target_positions()[k].x();
      t(k, 1) = e.target_positions()[k].y();
    }
    py::dict truth;
    truth["target_positions"] = truth_positions;
    py::dict state;
    state["step"] = e.step();
    state["positions"] = positions;
    state["lattice"] = lattice_index;
    state["cells"] = cells;
    state["active"] = active;
    state["neighbors"] = neighbors;
    state["mean"] = mean;
    state["cov"] = cov;
    state["det"] = det;
    state["log_det_prior"] = py::array_t<double>(static_cast<py::ssize_t>(m),
                                                 e.log_det_prior().data());
    state["eps"] = e.mission().eps;
    state["truth"] = truth;
    return state;
  }

  py::dict Step(const py::array_t<long long>& moves) {
    if (episode_->done())
      throw py::value_error("step: the mission is done (done is True)");
    external_->next = MovesFrom(moves, num_robots());
    const long invalid_before = episode_->invalid_moves();
    {
      py::gil_scoped_release release;
      episode_->Step();
    }
    if (episode_->done()) {
      moves_.OnEnd(*episode_);
      estimate_.OnEnd(*episode_);
    }
    py::dict changed;
    changed["step"] = episode_->step();
    changed["invalid_moves"] = episode_->invalid_moves() - invalid_before;
    changed["localized"] = episode_->NumLocalized();
    changed["done"] = episode_->done();
    changed["success"] = episode_->success();
    return changed;
  }

  std::string SummaryText() const {
    return SummaryJson(Summarize(*episode_, 0.0), *episode_);
  }
  std::string DiagnosticsText() const {
    return DiagnosticsJson(*episode_, moves_, estimate_, 0.0);
  }

 private:
  std::uint64_t id_;
  std::shared_ptr<const Instance> instance_;
  ExternalPolicy* external_ = nullptr;  // owned by the episode
  std::unique_ptr<Episode> episode_;
  MoveObserver moves_;
  EstimateObserver estimate_;
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
      throw InputError("builtin_policy", 0, "name",
                       registry.UnknownPolicy(name));
    // On any valid scenario: only its policy section is read.
    spec_ = registry.Resolve(WithOverrides(GeneratedScenario(1, 1, 0), o));
  }

  const std::string& name() const { return spec_->name(); }
  bool centralized() const { return spec_->centralized(); }

  // One move per robot from what the robots know at this step (the team's
  // belief only for a centralized policy). The policy starts afresh (Reset
  // with the mission's seed) on a new mission or a step that is not the
  // next one, so that deciding at every step repeats `aia run`.
  py::array_t<long long> Decide(const Mission& mission) {
    const Episode& e = mission.episode();
    if (!policy_ || mission.id() != mission_id_ || e.step() != next_step_) {
      policy_ = spec_->Create();
      policy_->Reset(e.world().map, mission.num_robots(), mission.num_targets(),
                     e.scenario().seed);
      mission_id_ = mission.id();
    }
    DecisionContext ctx = e.Context();
    if (!policy_->centralized()) ctx.central = nullptr;
    moves_.assign(mission.num_robots(), Move::kStay);
    {
      py::gil_scoped_release release;
      status_ = policy_->Decide(ctx, &moves_);
    }
    next_step_ = e.step() + 1;
    py::array_t<long long> out(static_cast<py::ssize_t>(moves_.size()));
    auto v = out.mutable_unchecked<1>();
    for (std::size_t i = 0; i < moves_.size(); ++i)
      v(static_cast<py::ssize_t>(i)) = static_cast<long long>(moves_[i]);
    return out;
  }
  std::string LastStatus() const {
    return std::string(PolicyStatusName(status_));
  }

 private:
  std::shared_ptr<const PolicySpec> spec_;
  std::unique_ptr<Policy> policy_;
  std::uint64_t mission_id_ = 0;
  int next_step_ = -1;
  std::vector<Move> moves_;
  PolicyStatus status_ = PolicyStatus::kOk;
};

}  // namespace
}  // namespace python
}  // namespace aia

PYBIND11_MODULE(_aia, m) {
  using aia::python::BuiltinPolicy;
  using aia::python::Mission;
  m.doc() = "aia's C++ core (use the aia package)";
  static py::exception<aia::InputError> input_error(m, "InputError",
                                                    PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const aia::InputError& e) {
      // A scenario's bytes need not be UTF-8: shown escaped, not lost.
      const std::string text = e.Format();
      PyObject* message = PyUnicode_DecodeUTF8(
          text.data(), static_cast<Py_ssize_t>(text.size()),
          "backslashreplace");
      PyErr_SetObject(input_error.ptr(), message);
      Py_XDECREF(message);
    }
  });

  py::class_<Mission>(m, "Mission")
      .def(py::init<const std::string&, std::optional<std::uint64_t>,
                    const aia::python::KeyValues&>(),
           py::arg("scenario"), py::arg("seed") = py::none(),
           py::arg("overrides") = aia::python::KeyValues{})
      .def("state", &Mission::State)
      .def("step", &Mission::Step, py::arg("moves"))
      .def("summary_json", &Mission::SummaryText)
      .def("diagnostics_json", &Mission::DiagnosticsText)
      .def_property_readonly("num_robots", &Mission::num_robots)
      .def_property_readonly("num_targets", &Mission::num_targets)
      .def_property_readonly(
          "step_count", [](const Mission& s) { return s.episode().step(); })
      .def_property_readonly(
          "done", [](const Mission& s) { return s.episode().done(); })
      .def_property_readonly(
          "success", [](const Mission& s) { return s.episode().success(); })
      .def_property_readonly(
          "flowtime", [](const Mission& s) { return s.episode().flowtime(); })
      .def_property_readonly(
          "max_steps",
          [](const Mission& s) { return s.episode().mission().max_steps; })
      .def_property_readonly(
          "seed", [](const Mission& s) { return s.episode().scenario().seed; });

  py::class_<BuiltinPolicy>(m, "BuiltinPolicy")
      .def(py::init<const std::string&, const aia::python::KeyValues&>(),
           py::arg("name"), py::arg("params") = aia::python::KeyValues{})
      .def("decide", &BuiltinPolicy::Decide, py::arg("mission"))
      .def_property_readonly("name", &BuiltinPolicy::name)
      .def_property_readonly("centralized", &BuiltinPolicy::centralized)
      .def_property_readonly("last_status", &BuiltinPolicy::LastStatus);

  m.def("policy_names", [] { return aia::AllPolicies().Names(); });
}
