/* A C-level VRPN sender for bench/bench_vrpn.py --part csender: the baseline of serve's fan-out cost.
   Accepts CLIENTS direct TCP clients, exchanges cookies, describes one tracker and the
   Pos_Quat type, then every 1/RATE s sends each client SENSORS pose messages (88 bytes
   each, one send per client), for SECONDS. Usage: sender CLIENTS SENSORS RATE SECONDS */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

static const char COOKIE[24] = "vrpn: ver. 07.38  0";

static size_t put32(unsigned char *p, uint32_t v) {
    v = htonl(v);
    memcpy(p, &v, 4);
    return 4;
}

static size_t put64(unsigned char *p, double d) {
    uint64_t v;
    memcpy(&v, &d, 8);
    v = ((uint64_t)htonl((uint32_t)v) << 32) | htonl((uint32_t)(v >> 32));
    memcpy(p, &v, 8);
    return 8;
}

static size_t header(unsigned char *p, uint32_t length, int32_t sender, int32_t type) {
    struct timeval tv;
    gettimeofday(&tv, NULL);
    put32(p, length);
    put32(p + 4, (uint32_t)tv.tv_sec);
    put32(p + 8, (uint32_t)tv.tv_usec);
    put32(p + 12, (uint32_t)sender);
    put32(p + 16, (uint32_t)type);
    put32(p + 20, 0);
    return 24;
}

static size_t describe(unsigned char *p, int32_t kind, int32_t id, const char *name) {
    size_t n = strlen(name) + 1, body = 4 + n, padded = (body + 7) & ~(size_t)7;
    header(p, (uint32_t)(24 + body), id, kind);
    memset(p + 24, 0, padded);
    put32(p + 24, (uint32_t)n);
    memcpy(p + 28, name, n);
    return 24 + padded;
}

int main(int argc, char **argv) {
    if (argc != 5) return 2;
    int clients = atoi(argv[1]), sensors = atoi(argv[2]);
    double rate = atof(argv[3]), seconds = atof(argv[4]);
    int ls = socket(AF_INET, SOCK_STREAM, 0), one = 1;
    setsockopt(ls, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof a;
    if (bind(ls, (struct sockaddr *)&a, sizeof a) || listen(ls, 64)) return 1;
    getsockname(ls, (struct sockaddr *)&a, &len);
    printf("%d\n", ntohs(a.sin_port));
    fflush(stdout);
    int *fds = calloc((size_t)clients, sizeof *fds);
    unsigned char setup[256], *poses = malloc((size_t)sensors * 88);
    size_t n = describe(setup, -1, 0, "Tracker0");
    n += describe(setup + n, -2, 6, "vrpn_Tracker Pos_Quat");
    for (int i = 0; i < clients; i++) {
        fds[i] = accept(ls, NULL, NULL);
        setsockopt(fds[i], IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        char cookie[24];
        size_t got = 0;
        while (got < 24) {
            ssize_t r = recv(fds[i], cookie + got, 24 - got, 0);
            if (r <= 0) return 1;
            got += (size_t)r;
        }
        send(fds[i], COOKIE, 24, 0);
        send(fds[i], setup, n, 0);
    }
    printf("ready\n");
    fflush(stdout);
    struct timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    long period = (long)(1e9 / rate), ticks = (long)(seconds * rate);
    for (long tick = 0; tick < ticks; tick++) {
        next.tv_nsec += period;
        while (next.tv_nsec >= 1000000000L) {
            next.tv_nsec -= 1000000000L;
            next.tv_sec++;
        }
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
        double t = (double)tick / rate;
        for (int s = 0; s < sensors; s++) {
            unsigned char *p = poses + (size_t)s * 88;
            p += header(p, 88, 0, 6);
            p += put32(p, (uint32_t)s);
            p += put32(p, 0);
            p += put64(p, 0.5 * t);
            p += put64(p, 1.5);
            p += put64(p, -0.25 * s);
            p += put64(p, 0.0);
            p += put64(p, 0.0);
            p += put64(p, 0.0);
            p += put64(p, 1.0);
        }
        for (int i = 0; i < clients; i++)
            send(fds[i], poses, (size_t)sensors * 88, MSG_DONTWAIT | MSG_NOSIGNAL);
    }
    for (int i = 0; i < clients; i++) close(fds[i]);
    return 0;
}
