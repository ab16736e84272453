#pragma once
// Test helper: a whole buffer deflated into one zlib stream (for hand-made replay bodies).

#include <gtest/gtest.h>
#include <zlib.h>

#include <string>

namespace overtake::test {

inline std::string deflate_all(const std::string& raw) {
  uLongf n = compressBound(static_cast<uLong>(raw.size()));
  std::string out(n, '\0');
  EXPECT_EQ(compress(reinterpret_cast<Bytef*>(out.data()), &n,
                     reinterpret_cast<const Bytef*>(raw.data()), static_cast<uLong>(raw.size())),
            Z_OK);
  out.resize(n);
  return out;
}

}  // namespace overtake::test
