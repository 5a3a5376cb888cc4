// A third-party library that returns Eigen arrays, compiled the ordinary way (no msdeform settings).
#include <Eigen/Core>

Eigen::VectorXd other_ones(int n) { return Eigen::VectorXd::Constant(n, 1.0); }
