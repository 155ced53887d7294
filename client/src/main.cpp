// The `mdem` binary: everything lives in the mdem_cli library (client/src/cli.cpp).
#include "mdem/cli.h"

int main(int argc, char** argv) { return mdem::cli::main(argc, argv); }
