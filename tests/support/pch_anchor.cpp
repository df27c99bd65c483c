// The translation unit tests/CMakeLists.txt compiles the suite's precompiled header with.
