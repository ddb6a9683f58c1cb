#include "memory.h"

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/resource.h>
#include <unistd.h>

namespace mvpt {

namespace {

double page_bytes() { return double(sysconf(_SC_PAGESIZE)); }

/// MemAvailable of /proc/meminfo (else 80 % of the physical memory).
double machine_available() {
    std::ifstream meminfo("/proc/meminfo");
    std::string line;
    while (std::getline(meminfo, line))
        if (line.rfind("MemAvailable:", 0) == 0) {
            std::istringstream in(line.substr(13));
            double kib = 0.0;
            if (in >> kib) return kib * 1024.0;
        }
    const double pages = double(sysconf(_SC_PHYS_PAGES));
    return pages > 0 && page_bytes() > 0 ? 0.8 * pages * page_bytes() : 0.0;
}

/// What RLIMIT_AS leaves of the address space (-1: no limit).
double address_space_left() {
    rlimit lim{};
    if (getrlimit(RLIMIT_AS, &lim) != 0 || lim.rlim_cur == RLIM_INFINITY) return -1.0;
    std::ifstream statm("/proc/self/statm");
    double size = 0.0;
    if (!(statm >> size)) return -1.0;
    return std::max(0.0, double(lim.rlim_cur) - size * page_bytes());
}

double read_number(const std::string &path) {
    std::ifstream in(path);
    std::string word;
    if (!(in >> word) || word == "max") return -1.0;
    try {
        return std::stod(word);
    } catch (...) {
        return -1.0;
    }
}

/// What the limit of this process's cgroup leaves (-1: none): v2's memory.max - memory.current.
double cgroup_left() {
    std::ifstream self("/proc/self/cgroup");
    std::string line;
    while (std::getline(self, line)) {
        if (line.rfind("0::", 0) != 0) continue;
        const std::string dir = "/sys/fs/cgroup" + line.substr(3);
        const double max = read_number(dir + "/memory.max"), current = read_number(dir + "/memory.current");
        if (max >= 0.0 && current >= 0.0) return std::max(0.0, max - current);
    }
    const double max = read_number("/sys/fs/cgroup/memory.max"), current = read_number("/sys/fs/cgroup/memory.current");
    return max >= 0.0 && current >= 0.0 ? std::max(0.0, max - current) : -1.0;
}

} // namespace

double resident_bytes() {
    std::ifstream statm("/proc/self/statm");
    double size = 0.0, resident = 0.0;
    if (!(statm >> size >> resident)) return 0.0;
    return resident * page_bytes();
}

MemoryRoom available_memory() {
    MemoryRoom room{machine_available(), "the machine"};
    const double as = address_space_left(), cg = cgroup_left();
    if (as >= 0.0 && (room.bytes <= 0.0 || as < room.bytes)) room = {as, "the address-space limit (ulimit -v)"};
    if (cg >= 0.0 && (room.bytes <= 0.0 || cg < room.bytes)) room = {cg, "the memory limit of its cgroup (memory.max)"};
    return room;
}

} // namespace mvpt
