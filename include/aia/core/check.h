// Internal invariant checks. Bad *input* is reported with aia::InputError
// (see error.h); AIA_CHECK is for states that indicate a bug in aia itself.
#ifndef AIA_CORE_CHECK_H_
#define AIA_CORE_CHECK_H_

namespace aia::internal {
[[noreturn]] void CheckFailed(const char* expr, const char* file, int line,
                              const char* msg);
}  // namespace aia::internal

#define AIA_CHECK(cond)                                                       \
  do {                                                                        \
    if (!(cond)) ::aia::internal::CheckFailed(#cond, __FILE__, __LINE__, ""); \
  } while (false)

#define AIA_CHECK_MSG(cond, msg)                                      \
  do {                                                                \
    if (!(cond))                                                      \
      ::aia::internal::CheckFailed(#cond, __FILE__, __LINE__, (msg)); \
  } while (false)

#endif  // AIA_CORE_CHECK_H_
