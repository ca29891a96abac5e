// A minimal VRPN C++ client for bench/bench_vrpn_monitor.py: reads a tracker with VRPN's own
// vrpn_Tracker_Remote (the lob and a UDP channel, as any C++ client does) for SECONDS and
// prints one line: reports received, CPU seconds (user + system), wall seconds.
// Build against the vrpn/vrpn sources (not part of gadgetctl), see the benchmark's notes.
#include <cstdio>
#include <cstdlib>
#include <sys/resource.h>
#include "vrpn_Tracker.h"

static long reports = 0;
static void VRPN_CALLBACK on_pose(void *, const vrpn_TRACKERCB) { ++reports; }

static double cpu() {
    struct rusage u;
    getrusage(RUSAGE_SELF, &u);
    return u.ru_utime.tv_sec + u.ru_utime.tv_usec * 1e-6 + u.ru_stime.tv_sec + u.ru_stime.tv_usec * 1e-6;
}

int main(int argc, char **argv) {
    if (argc < 3) { fprintf(stderr, "usage: %s Device@host SECONDS\n", argv[0]); return 2; }
    vrpn_Tracker_Remote tracker(argv[1]);
    tracker.register_change_handler(NULL, on_pose);
    double seconds = atof(argv[2]);
    struct timeval start, now;
    vrpn_gettimeofday(&start, NULL);
    do {  // connect first: until the first report
        tracker.mainloop();
        vrpn_SleepMsecs(1);
        vrpn_gettimeofday(&now, NULL);
    } while (reports == 0 && vrpn_TimevalDurationSeconds(now, start) < 10);
    reports = 0;
    double cpu0 = cpu();
    vrpn_gettimeofday(&start, NULL);
    do {
        tracker.mainloop();
        vrpn_SleepMsecs(1);
        vrpn_gettimeofday(&now, NULL);
    } while (vrpn_TimevalDurationSeconds(now, start) < seconds);
    printf("%ld %.6f %.6f\n", reports, cpu() - cpu0, vrpn_TimevalDurationSeconds(now, start));
    return 0;
}
