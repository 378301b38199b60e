#pragma once
// The loose lever-arm reference bound of the certificate, kept beside the tests and the benchmark
// that compare it with the Taylor bound (docs/algorithm.md, "Certified intervals"): the link's box
// at the leaf's centre grown on every side by sum_i h_i (lever_i + corner) (h_i for a slide), the
// most the link can move, against the obstacle's box.
#include "leeway/core/swept_link.hpp"

namespace leeway {

class LeverBound final : public SweepBound {
 public:
  bool separated(const SweptLink& link, const SweepObstacle& obstacle, double margin) const override {
    return !touches(link.box(), link.lever_radius() + margin, obstacle.box, obstacle.plane);
  }
  double contribution(const SweptLink& link, size_t p, double w) const override {
    const LinkChain& chain = link.link();
    return w * (chain.slide[p] ? 1.0 : chain.lever[p] + chain.corner_lever);
  }
};

}  // namespace leeway
