// The parameters of map reuse: within a run (keep_map: dormant landmarks found again; revisit_*,
// descriptor_*, dormant_*, search_*) and across runs (map_relocalize: the kept map and the
// relocalization in it; relocalize_*, max_kept_points). Their names, defaults, ranges and units are written once, in
// the node's parameter table (src/ros/param_table.cc, docs/parameters.md).
#pragma once

namespace vi_ekf_slam {

struct MapReuseParams {
  /// Within a run (keep_map): keep landmarks whose tracks ended (with a descriptor) as dormant,
  /// and find them again (experimental: docs/evaluation.md has what it gains and costs).
  bool within_run = false;
  /// Dormant landmarks kept [count], in the room the tracked ones leave below max_landmarks;
  /// beyond it the most crowded places give up points.
  int max_dormant = 100;
  /// The matches of one image must agree (joint compatibility of their stacked innovation at the
  /// update's gate probability); fewer than this many agreeing matches are none [count].
  int min_joint_revisits = 2;
  /// A match is believed only after its track has landed where the landmark is predicted in this
  /// many images, the one it was found in included (pendingRevisitAgrees); 1: at once. A
  /// look-alike at another depth drifts off as the camera moves; a real front end loses many
  /// corners it found again within an image or two, so waiting also loses true revisits
  /// (docs/evaluation.md has both) [count].
  int revisit_confirm_frames = 1;
  /// Only a landmark whose position's std-dev is at most this fraction of its distance is kept
  /// as dormant and searched for: a point whose depth the images have not settled would be found
  /// again in the wrong place [ratio].
  double max_relative_sigma = 0.1;
  /// Dormant points are consider states (Schmidt-Kalman, Landmark::consider): while unobserved,
  /// the updates of the other points leave them as they were instead of sharpening them through
  /// the pose they share (information the linearization invents over a long dormancy); seen
  /// again, the first update corrects the pose by them, and from the next on they are points of
  /// the filter again.
  bool dormant_consider = true;
  /// Dormant points are counted in cells of this size: the cell with the most gives up its least
  /// certain point first, so the kept map covers every place walked [m].
  double dormant_spacing_m = 1.0;
  /// A match's Hamming distance may be at most this [bits of 256] (ORB-SLAM's strict threshold).
  int max_descriptor_distance = 50;
  /// The best match's distance must be below this fraction of the second best's, both from the
  /// landmark's side (other features: in its region, or with distinct_in_view in the whole image,
  /// where the texture repeats, the region's one look-alike may be another point while the
  /// landmark itself was not detected) and from the feature's (landmarks whose region holds it)
  /// [ratio].
  double descriptor_ratio = 0.8;
  /// The landmark's side of the ratio test is over every other feature of the image (false: over
  /// its search region only).
  bool distinct_in_view = true;
  /// The search region: the chi^2 gate (2 dof) of this probability on the predicted pixel.
  double search_gate_probability = 0.99;
  /// A dormant landmark is searched for only while its predicted pixel's std-dev (the larger axis
  /// of its innovation covariance) is below this [px]: a region wider than that holds look-alikes.
  double max_search_sigma_px = 40.0;
  /// After a reset (or a map loaded from a file), place the new run in the kept map when the
  /// camera sees mapped points again (map_reuse/kept_map.h).
  bool across_runs = true;
  /// Points kept across runs (and saved) [count]; the first archived leave first.
  int max_kept_points = 2000;
  /// Matches that must agree on the camera's pose for a relocalization [count].
  int relocalize_min_inliers = 12;
  /// A match agrees when it reprojects within this under the pose [px].
  double relocalize_reprojection_px = 3.0;
  /// The PnP camera's gravity may differ from the filter's by at most this [deg]: both worlds are
  /// gravity-aligned, a larger tilt is a false relocalization.
  double relocalize_max_tilt_deg = 5.0;

  /// The map outlives the filter's runs (resets, a loaded file) and a new run is placed in it.
  bool keptAcrossRuns() const { return within_run && across_runs; }
};

}  // namespace vi_ekf_slam
