#include "aia/planning/node_arena.h"

#include <sys/mman.h>

#include <algorithm>
#include <new>
#include <type_traits>

namespace aia {
namespace {

// Blocks from this size on are mapped (ArenaAllocator).
constexpr std::size_t kMappedBytes = std::size_t{1} << 20;

}  // namespace

template <typename T>
T* ArenaAllocator<T>::allocate(std::size_t n) {
  const std::size_t bytes = n * sizeof(T);
  if (bytes < kMappedBytes) return static_cast<T*>(::operator new(bytes));
  void* p = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE,
                   MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
  return static_cast<T*>(p);
}

template <typename T>
void ArenaAllocator<T>::deallocate(T* p, std::size_t n) {
  const std::size_t bytes = n * sizeof(T);
  if (bytes < kMappedBytes) {
    ::operator delete(p);
  } else {
    ::munmap(p, bytes);
  }
}

template struct ArenaAllocator<int>;
template struct ArenaAllocator<double>;

void NodeArena::Reset(int robots, int stride) {
  n_ = robots;
  stride_ = stride;
  pos_.clear();
  info_.clear();
  parent_.clear();
  depth_.clear();
  unloc_.clear();
  cost_.clear();
  det_sum_.clear();
  lower_.clear();
}

int NodeArena::MaxDepth() const {
  return *std::max_element(depth_.begin(), depth_.end());
}

double* NodeArena::Open(const int* positions) {
  const std::size_t id = parent_.size();
  pos_.insert(pos_.end(), positions, positions + n_);
  info_.resize(info_.size() + stride_);
  return info_.data() + id * stride_;
}

void NodeArena::Close(int parent, int depth, int unloc, double det_sum,
                      double cost, double lower) {
  parent_.push_back(parent);
  depth_.push_back(depth);
  unloc_.push_back(unloc);
  det_sum_.push_back(det_sum);
  cost_.push_back(cost);
  lower_.push_back(lower);
}

void NodeArena::Reserve(std::size_t nodes) {
  pos_.reserve(nodes * n_);
  info_.reserve(nodes * stride_);
  for (auto* v : {&parent_, &depth_, &unloc_}) v->reserve(nodes);
  for (auto* v : {&cost_, &det_sum_, &lower_}) v->reserve(nodes);
}

void NodeArena::Release() {
  const auto release = [](auto& v) { std::decay_t<decltype(v)>().swap(v); };
  release(pos_);
  release(info_);
  release(parent_);
  release(depth_);
  release(unloc_);
  release(cost_);
  release(det_sum_);
  release(lower_);
}

std::size_t NodeArena::bytes() const {
  return pos_.size() * sizeof(int) + info_.size() * sizeof(double) +
         (parent_.size() + depth_.size() + unloc_.size()) * sizeof(int) +
         (cost_.size() + det_sum_.size() + lower_.size()) * sizeof(double);
}

}  // namespace aia
