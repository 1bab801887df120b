// The property check of every fuzz target (scripts/fuzz.sh puts this folder on the include path): a
// violated property is named, then the target aborts so that libFuzzer keeps the input.
#pragma once

#include <cstdio>
#include <cstdlib>

#define check(ok)                                                                       \
  do                                                                                    \
  {                                                                                     \
    if (!(ok))                                                                          \
    {                                                                                   \
      std::fprintf(stderr, "property violated: %s (%s:%d)\n", #ok, __FILE__, __LINE__); \
      std::abort();                                                                     \
    }                                                                                   \
  } while (false)
