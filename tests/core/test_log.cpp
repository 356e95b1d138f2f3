// The levelled log: what each level lets through.
#include <gtest/gtest.h>

#include "core/log.hpp"

namespace eds {
namespace {

TEST(Log, EachLevelLetsThroughItselfAndWhatIsMoreSevere) {
  setLogLevel(LogLevel::kInfo);
  EXPECT_TRUE(logEnabled(LogLevel::kError));
  EXPECT_TRUE(logEnabled(LogLevel::kWarn));
  EXPECT_TRUE(logEnabled(LogLevel::kInfo));
  EXPECT_FALSE(logEnabled(LogLevel::kDebug));
  setLogLevel(LogLevel::kError);
  EXPECT_FALSE(logEnabled(LogLevel::kWarn));
  setLogLevel(LogLevel::kDebug);
  EXPECT_TRUE(logEnabled(LogLevel::kDebug));
  setLogLevel(LogLevel::kWarn);  // the default, for the tests that follow
  EXPECT_FALSE(logEnabled(LogLevel::kInfo));
}

}  // namespace
}  // namespace eds
