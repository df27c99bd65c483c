// The donor of the test executables' shared precompiled header (tests/CMakeLists.txt): CMake
// builds the header from this target; the file itself has nothing to compile.
