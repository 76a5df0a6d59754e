"""Layer 6, toolchain: a generated folder compiled with CMake into a content-addressed cache,
its kernels loaded with ctypes, its driver run and its rows read back."""
