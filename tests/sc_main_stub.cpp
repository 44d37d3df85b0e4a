// SystemC's library defines main() and calls sc_main(); the test binaries take
// main() from gtest_main instead, but the linker still needs an sc_main symbol.
extern "C" int sc_main(int, char*[]) { return 0; }
