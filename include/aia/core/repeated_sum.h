// s + v + v + ... (count additions of one double, each rounded as IEEE
// double addition rounds it), to the bit, in O(binades crossed) instead of
// O(count). A sum over many equal terms (the DKF's column sum in a full
// graph, where most robots hold one belief of a target bit for bit:
// docs/design.md, Estimation) costs then what its distinct terms cost.
#ifndef AIA_CORE_REPEATED_SUM_H_
#define AIA_CORE_REPEATED_SUM_H_

#include <cstdint>

namespace aia {

// The value of `for (count times) s += v;` in double arithmetic with
// round-to-nearest-even (no excess precision, no fused operations), for any
// s and v (zeros of either sign, subnormals, infinities, NaN) and count >= 0.
double AddRepeated(double s, double v, std::int64_t count);

}  // namespace aia

#endif  // AIA_CORE_REPEATED_SUM_H_
