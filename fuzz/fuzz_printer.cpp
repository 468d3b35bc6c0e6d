// Printer profiles (printers/*.toml): parse_printer.
#include <string>

#include "fuzz/fuzz.hpp"
#include "print/printer.hpp"

using namespace rfd;

RFD_FUZZ_TARGET(printer) { print::parse_printer(std::string(fuzz::text(data, size)), "fuzz.toml"); }
