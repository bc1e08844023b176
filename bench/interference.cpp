#include "interference.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <string>

namespace kdrt::bench {

namespace {

// CPU seconds the whole machine spent busy (user, nice, system, irq, softirq, steal).
double machine_busy_s() {
    std::ifstream in("/proc/stat");
    std::string cpu;
    unsigned long long user = 0, nice = 0, system = 0, idle = 0, iowait = 0, irq = 0, softirq = 0, steal = 0;
    if (!(in >> cpu >> user >> nice >> system >> idle >> iowait >> irq >> softirq >> steal)) return 0.0;
    const double hz = static_cast<double>(sysconf(_SC_CLK_TCK));
    return static_cast<double>(user + nice + system + irq + softirq + steal) / hz;
}

double seconds(const timeval& t) { return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6; }

// CPU seconds used by this process (all threads) and its reaped children.
double own_s() {
    rusage self{}, children{};
    getrusage(RUSAGE_SELF, &self);
    getrusage(RUSAGE_CHILDREN, &children);
    return seconds(self.ru_utime) + seconds(self.ru_stime) + seconds(children.ru_utime) + seconds(children.ru_stime);
}

}  // namespace

void Interference::restart() {
    busy_s_ = machine_busy_s();
    self_s_ = own_s();
    clock_.restart();
}

double Interference::other_cores() const {
    const double wall = elapsed_s();
    if (wall <= 0.0) return 0.0;
    return std::max(0.0, ((machine_busy_s() - busy_s_) - (own_s() - self_s_)) / wall);
}

}  // namespace kdrt::bench
