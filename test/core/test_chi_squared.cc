#include <gtest/gtest.h>

#include "vi_ekf_slam/core/chi_squared.h"

using namespace vi_ekf_slam;

// Reference quantiles from standard chi-square tables (R: qchisq).
TEST(ChiSquared, QuantilesMatchTables) {
  EXPECT_NEAR(chiSquaredQuantile(0.95, 2), 5.991464547107979, 1e-9);
  EXPECT_NEAR(chiSquaredQuantile(0.95, 3), 7.814727903251178, 1e-9);
  EXPECT_NEAR(chiSquaredQuantile(0.99, 1), 6.634896601021214, 1e-9);
  EXPECT_NEAR(chiSquaredQuantile(0.95, 6), 12.591587243743977, 1e-9);
  EXPECT_NEAR(chiSquaredQuantile(0.5, 1), 0.454936423119572, 1e-9);
  EXPECT_NEAR(chiSquaredQuantile(0.025, 300), 253.912, 1e-2);
  EXPECT_NEAR(chiSquaredQuantile(0.975, 300), 349.874, 1e-2);
}

TEST(ChiSquared, CdfInvertsQuantile) {
  for (double dof : {1.0, 2.0, 6.0, 30.0, 300.0}) {
    for (double p : {0.01, 0.3, 0.95, 0.999}) {
      EXPECT_NEAR(chiSquaredCdf(chiSquaredQuantile(p, dof), dof), p, 1e-10);
    }
  }
}

TEST(ChiSquared, RejectsBadArguments) {
  EXPECT_THROW(chiSquaredQuantile(1.0, 2), std::invalid_argument);
  EXPECT_THROW(chiSquaredQuantile(0.5, 0), std::invalid_argument);
}
