// Example 2: the bounds in a control loop. A bounds file (format leeway-bounds-2, e.g. written by
// example 1) is read without its cell; a 100 Hz loop follows the nominal path while a simulated
// person (a seeded random walk of up to +-0.4 rad per joint) pushes the arm off it and, at times,
// holds it back or hurries it on. The controller tracks its own progress along the path and clamps
// every command into the box of the path parameter s it is at: the guarantee is in s, not in the
// nominal time t (docs/cli.md, "Contract for a controller").
//
//   leeway-example-02 BOUNDS.json [SEED]
//
// Prints how often each joint was clamped; exits 1 if a command ever left its box (it cannot).
#include <algorithm>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "leeway/core/error.hpp"
#include "leeway/io/bounds_file.hpp"

int main(int argc, char** argv) {
  using namespace leeway;
  if (argc < 2) {
    std::fprintf(stderr, "usage: leeway-example-02 BOUNDS.json [SEED]\n");
    return 2;
  }
  try {
    const BoundsFile file = read_bounds_file(argv[1]);
    const BoundsTrajectory& bounds = file.trajectory;
    const int n = bounds.dof();
    std::mt19937_64 rng(argc > 2 ? std::stoull(argv[2]) : 1);
    std::normal_distribution<double> kick(0.0, 0.02);       // push increments [rad per step]
    std::uniform_real_distribution<double> pace(0.3, 1.3);  // the person's pace, x nominal
    const double dt = 0.01;                                 // control period [s]
    Eigen::VectorXd push = Eigen::VectorXd::Zero(n), nominal(n), lower(n), upper(n), command(n);
    std::vector<long> clamped(static_cast<size_t>(n), 0);
    double progress = 0;  // nominal time reached so far [s]; not the wall clock
    double rate = 1;
    long steps = 0, outside = 0;
    while (progress < bounds.duration() || steps == 0) {
      if (steps % 50 == 0) rate = pace(rng);  // every half second a new pace
      progress = std::min(bounds.duration(), progress + rate * dt);
      const double s = bounds.s_at_t(progress);  // where on the path the robot is
      bounds.at_s(s, nominal, lower, upper);
      for (int j = 0; j < n; ++j) {
        push[j] = std::clamp(push[j] + kick(rng), -0.4, 0.4);
        const double wanted = nominal[j] + push[j];
        command[j] = std::clamp(wanted, lower[j], upper[j]);
        clamped[static_cast<size_t>(j)] += command[j] != wanted;
      }
      outside += !bounds.contains(s, command);
      ++steps;
      if (progress >= bounds.duration()) break;
    }
    std::printf("%s: %ld steps of %.0f ms over %.3f s of nominal path; commands outside their box: %ld\n",
                argv[1], steps, dt * 1000, bounds.duration(), outside);
    for (int j = 0; j < n; ++j)
      std::printf("  %s clamped in %ld of %ld steps\n", file.joints[static_cast<size_t>(j)].c_str(),
                  clamped[static_cast<size_t>(j)], steps);
    return outside == 0 ? 0 : 1;
  } catch (const InputError& e) {
    std::fprintf(stderr, "leeway-example-02: %s\n", e.what());
    return 2;
  }
}
