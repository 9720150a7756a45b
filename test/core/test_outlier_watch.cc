// The gate the update uses: narrow (gate_probability) until the tracks, seen while moving, have
// gone clean_gate_s seconds without an outlier; any outlier narrows it again.
#include <gtest/gtest.h>

#include "vi_ekf_slam/core/outlier_watch.h"

using namespace vi_ekf_slam;

namespace {
UpdateResult frame(int outliers) {
  UpdateResult r;
  r.accepted = 40;
  r.rejected_ids.assign(2, 7);
  r.outliers = outliers;
  return r;
}
}  // namespace

TEST(OutlierWatch, WidensAfterCleanMovingSecondsAndNarrowsAtAnOutlier) {
  UpdateParams p;  // 0.95, then 0.9999 after 1 s
  OutlierWatch w;
  EXPECT_EQ(w.gateProbability(p), p.gate_probability);  // outliers assumed at a start
  double t = 0.0;
  const double dt = 0.25;  // (exact in binary: the seconds add up exactly)
  for (int i = 0; i < 8; ++i, t += dt) w.record(frame(0), false, t, p);  // 2 s at rest: not counted
  EXPECT_EQ(w.cleanSeconds(), 0.0);
  EXPECT_EQ(w.gateProbability(p), p.gate_probability);
  for (int i = 0; i < 4; ++i, t += dt) w.record(frame(0), true, t, p);  // 0.75 s from the first to the last
  EXPECT_EQ(w.cleanSeconds(), 0.75);
  EXPECT_EQ(w.gateProbability(p), p.gate_probability);
  w.record(frame(0), true, t, p);
  t += dt;
  EXPECT_EQ(w.gateProbability(p), p.clean_gate_probability);
  w.record(frame(1), true, t, p);  // one outlier among 42
  t += dt;
  EXPECT_EQ(w.cleanSeconds(), 0.0);
  EXPECT_EQ(w.gateProbability(p), p.gate_probability);
  w.record(frame(0), false, t, p);  // a stand in between: its seconds do not count
  t += 5.0;
  for (int i = 0; i < 4; ++i, t += dt) w.record(frame(0), true, t, p);
  EXPECT_EQ(w.cleanSeconds(), 0.75);
  w.record(frame(0), true, t, p);
  EXPECT_EQ(w.gateProbability(p), p.clean_gate_probability);
  w.reset();  // a reset: outliers assumed again
  EXPECT_EQ(w.gateProbability(p), p.gate_probability);
}

TEST(OutlierWatch, OneGateWhenTheCleanGateIsNotWider) {
  UpdateParams p;
  p.clean_gate_s = 0.0;
  OutlierWatch w;
  EXPECT_EQ(w.gateProbability(p), p.clean_gate_probability);  // no seconds asked: always wide
  p.clean_gate_probability = 0.9;                             // narrower than the gate: the gate
  EXPECT_EQ(w.gateProbability(p), p.gate_probability);
}
