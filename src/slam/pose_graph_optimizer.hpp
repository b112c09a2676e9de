#pragma once
// Pose-graph optimization for loop correction (the essential graph of ORB-SLAM2, SE3 instead of
// Sim3 because RGB-D depth fixes the scale). Nodes are keyframe poses T_cw; an edge holds a
// measured relative pose T_ij = T_iw * T_jw^-1 (camera j to camera i) and a weight. The
// residual of an edge is the 6-vector [translation; angle-axis rotation] of
// T_ij_measured^-1 * T_iw * T_jw^-1, scaled by sqrt(weight). Ceres, Levenberg-Marquardt,
// sparse normal Cholesky.
//
// Plain data, so loop closing can fill it under the map lock and it can be tested on
// constructed graphs.
#include <vector>

#include "core/se3.hpp"

namespace builtscene::slam {

struct PoseGraph {
  struct Node {
    SE3 T_cw;
    bool fixed = false;
  };
  struct Edge {
    int i = 0, j = 0;
    SE3 T_ij;  // measured T_iw * T_jw^-1
    double weight = 1.0;
  };
  std::vector<Node> nodes;
  std::vector<Edge> edges;
};

struct PoseGraphOptions {
  int iterations = 20;  // ORB-SLAM2's essential-graph optimization runs 20
};

struct PoseGraphResult {
  std::vector<SE3> poses;  // per node (fixed ones and nodes without edges unchanged)
  double initial_cost = 0, final_cost = 0;
  bool solved = false;
};

// Without a fixed node the first node with an edge is held fixed (the gauge).
PoseGraphResult optimize_pose_graph(const PoseGraph& graph, const PoseGraphOptions& options = {});

}  // namespace builtscene::slam
