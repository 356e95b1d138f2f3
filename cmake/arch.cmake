# The instruction set the code is compiled for. The per-pixel and per-point loops are written for the
# compiler to vectorize; AVX2 and FMA (x86-64-v3, every x86 laptop and server CPU since about 2015)
# double their vector width over the x86-64 baseline and made whole runs 10-25 % faster
# (docs/experiments.md); compiled without contracting multiply-adds, they compute what the baseline
# does, up to the order of vector sums. The release preset asks for auto; the sanitizer presets keep
# the compiler's default (no figure depends on them).
# EDS_ARCH: "" (the compiler's default), "auto" (x86-64-v3 where the compiler accepts it and this
# machine runs it), or any -march value (native, x86-64-v3, ...).
set(EDS_ARCH "" CACHE STRING "-march for eds: empty for the compiler's default, auto for x86-64-v3 where this machine runs it, or a -march value")

if(EDS_ARCH STREQUAL "auto")
  set(_eds_arch "")
  if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(x86_64|AMD64|amd64)$" AND NOT CMAKE_CROSSCOMPILING)
    include(CheckCXXCompilerFlag)
    check_cxx_compiler_flag("-march=x86-64-v3" EDS_HAVE_MARCH_V3)
    if(EDS_HAVE_MARCH_V3)
      # The flag alone would build a program that stops on an older CPU with an illegal instruction.
      try_run(EDS_V3_RUN_RESULT EDS_V3_COMPILES SOURCE_FROM_CONTENT cpu_check.cpp
              "int main() { __builtin_cpu_init(); return __builtin_cpu_supports(\"avx2\") && __builtin_cpu_supports(\"fma\") && __builtin_cpu_supports(\"bmi2\") ? 0 : 1; }")
      if(EDS_V3_COMPILES AND EDS_V3_RUN_RESULT EQUAL 0)
        set(_eds_arch "x86-64-v3")
      endif()
    endif()
  endif()
else()
  set(_eds_arch "${EDS_ARCH}")
endif()

# With AVX Eigen would align its fixed-size types and its heap blocks to 32 bytes (64 with AVX-512),
# where Debian's Ceres, built for the x86-64 baseline, uses 16: objects passed between the two would
# differ in layout, and a block allocated on one side and freed on the other corrupts the heap (seen
# with -march=native). EIGEN_MAX_ALIGN_BYTES=16 keeps the baseline's layout; the vector instructions
# stay (unaligned loads). It is public on the library (src/CMakeLists.txt), so that a find_package(eds)
# build shares the layout whatever its own flags.
# No fused multiply-adds where the source has a multiply and an add: with them (GCC's default once the
# instruction set has FMA) every figure moved from the baseline build's, and the real slider's rotation
# error grew by a fifth over twenty runs. Without them the frames and keyframes come out as the baseline
# build's bit for bit (the event poses within rounding: wider vector sums), about 3 % slower
# (docs/experiments.md).
set(EDS_ARCH_DEFINITIONS "")
if(_eds_arch)
  set(EDS_ARCH_DEFINITIONS "EIGEN_MAX_ALIGN_BYTES=16")
  add_compile_options("-march=${_eds_arch}" "-ffp-contract=off")
  add_compile_definitions(${EDS_ARCH_DEFINITIONS})
  message(STATUS "eds: compiling for -march=${_eds_arch}")
else()
  message(STATUS "eds: compiling for the compiler's default instruction set")
endif()
