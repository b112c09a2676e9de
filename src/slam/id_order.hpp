#pragma once
// Orders keyframes and map points by their id instead of their heap address.
//
// Why: a container keyed by pointer iterates in address order, and addresses change from run
// to run, so tie-breaks (the best covisible keyframe, the order of residuals in bundle
// adjustment, database candidates) changed too and the same input gave different
// trajectories. Ids are assigned in processing order, so every container of keyframes or
// points that is iterated uses these instead.
#include <cstddef>
#include <functional>
#include <map>
#include <set>

namespace builtscene::slam {

class KeyFrame;
class MapPoint;

// Comparator for ordered containers of KeyFrame* or MapPoint* (const or not). A template, so
// it can be named where the pointee is still incomplete.
struct ById {
  template <class T>
  bool operator()(const T* a, const T* b) const {
    return a->id < b->id;
  }
};

// Hash for unordered containers: with the same ids inserted in the same order, iteration
// order is the same in every run.
struct HashById {
  template <class T>
  std::size_t operator()(const T* p) const {
    return std::hash<long>()(p->id);
  }
};

template <class V>
using KeyFrameMap = std::map<KeyFrame*, V, ById>;
using KeyFrameSet = std::set<KeyFrame*, ById>;

}  // namespace builtscene::slam
