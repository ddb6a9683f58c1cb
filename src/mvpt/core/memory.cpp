#include "memory.h"

#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace mvpt {

double resident_bytes() {
    std::ifstream statm("/proc/self/statm");
    double size = 0.0, resident = 0.0;
    if (!(statm >> size >> resident)) return 0.0;
    return resident * double(sysconf(_SC_PAGESIZE));
}

double available_bytes() {
    std::ifstream meminfo("/proc/meminfo");
    std::string line;
    while (std::getline(meminfo, line))
        if (line.rfind("MemAvailable:", 0) == 0) {
            std::istringstream in(line.substr(13));
            double kib = 0.0;
            if (in >> kib) return kib * 1024.0;
        }
    const double pages = double(sysconf(_SC_PHYS_PAGES)), page = double(sysconf(_SC_PAGESIZE));
    return pages > 0 && page > 0 ? 0.8 * pages * page : 0.0;
}

} // namespace mvpt
