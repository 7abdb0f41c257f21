// placeholder: tests land with the render module
#include <gtest/gtest.h>
TEST(Placeholder, render) { GTEST_SKIP() << "not written yet"; }
