#pragma once
// Orders keyframes and map points by their id instead of their heap address.
//
// Why: a container keyed by pointer iterates in address order, and addresses change from run
// to run, so tie-breaks (the best covisible keyframe, the order of residuals in bundle
// adjustment, database candidates) changed too and the same input gave different
// trajectories. Ids are assigned in processing order, so every container of keyframes or
// points that is iterated uses these instead.
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

template <class V>
using KeyFrameMap = std::map<KeyFrame*, V, ById>;
using KeyFrameSet = std::set<KeyFrame*, ById>;

}  // namespace builtscene::slam
