#pragma once
// Temporal consistency of loop candidates (ORB-SLAM2's idea, written here): a loop is only
// trusted when the place it points at keeps being recognised. Each candidate stands for a
// group (the candidate and its covisible keyframes). A group is consistent with a group of
// the previous keyframe's check when they share a keyframe; its consistency count is then one
// more than that group's, else 0. A candidate whose group reaches `required` (3: the place
// recognised on 4 consecutive keyframes, ORB-SLAM2's threshold) is accepted.
//
// Works on keyframe ids, so it needs no map and no lock; the loop-closing thread owns it.
#include <set>
#include <vector>

namespace builtscene::slam {

class LoopConsistency {
 public:
  explicit LoopConsistency(int required = 3) : required_(required) {}

  struct Candidate {
    long id = 0;              // the candidate keyframe
    std::vector<long> group;  // it and its covisible keyframes
  };
  // The candidates of the next checked keyframe; returns the accepted candidates' ids (in
  // the order given). An empty list breaks every chain.
  std::vector<long> update(const std::vector<Candidate>& candidates);
  // The candidates of the last update whose group fell one short of `required` (the place
  // recognised on every keyframe so far, but one keyframe too few): at the end of a run no
  // later keyframe can confirm them (LoopCloser::finish).
  const std::vector<long>& one_short() const { return one_short_; }
  void reset() {
    groups_.clear();
    one_short_.clear();
  }

  struct Group {
    std::set<long> members;
    int consistency = 0;
  };
  const std::vector<Group>& groups() const { return groups_; }

 private:
  int required_;
  std::vector<Group> groups_;
  std::vector<long> one_short_;
};

}  // namespace builtscene::slam
