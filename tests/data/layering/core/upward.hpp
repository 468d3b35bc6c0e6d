#pragma once
#include "optics/lens.hpp"  // core may not use optics
