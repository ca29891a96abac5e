// A VRPN 07.38 server built from the vrpn/vrpn C++ sources: waits for one client on
// 127.0.0.1:PORT, then sends a fixed script of tracker, button, analog, dial and text
// reports with fixed timestamps, then keeps serving until the client leaves.
// Usage: capture_server PORT [OUTGOING_LOG.vrpn]  (the library's own log of what it sent)
#include <cstdio>
#include <cstdlib>
#include "vrpn_Connection.h"
#include "vrpn_Tracker.h"
#include "vrpn_Button.h"
#include "vrpn_Analog.h"
#include "vrpn_Dial.h"
#include "vrpn_Text.h"

class ScriptDial : public vrpn_Dial {
public:
    ScriptDial(const char *name, vrpn_Connection *c) : vrpn_Dial(name, c) { num_dials = 3; }
    void mainloop() { server_mainloop(); }
    void send(double d0, double d1, double d2, timeval t) {
        dials[0] = d0; dials[1] = d1; dials[2] = d2; timestamp = t; report_changes();
    }
};

static timeval at(long sec, long usec) { timeval t; t.tv_sec = sec; t.tv_usec = usec; return t; }

int main(int argc, char **argv) {
    int port = argc > 1 ? atoi(argv[1]) : 3883;
    char name[64];
    snprintf(name, sizeof name, ":%d", port);
    const char *log = argc > 2 ? argv[2] : NULL;
    vrpn_Connection *c = vrpn_create_server_connection(port, NULL, log, "127.0.0.1");
    vrpn_Tracker_Server tracker("Tracker0", c, 3);
    vrpn_Button_Server button("Button0", c, 4);
    vrpn_Analog_Server analog("Analog0", c, 3);
    ScriptDial dial("Dial0", c);
    vrpn_Text_Sender text("Text0", c);
    fprintf(stderr, "listening on %d\n", port);
    while (!c->connected()) { c->mainloop(); vrpn_SleepMsecs(1); }
    for (int i = 0; i < 300; i++) {  // 0.3 s for the client's descriptions and pings
        tracker.mainloop(); button.mainloop(); analog.mainloop(); dial.mainloop(); text.mainloop();
        c->mainloop(); vrpn_SleepMsecs(1);
    }
    const double pos[3][3] = {{0.5, -1.0, 2.0}, {0.25, 0.125, -0.75}, {-3.5, 4.0, 0.0625}};
    const double quat[3][4] = {{0, 0, 0, 1}, {0.5, 0.5, 0.5, 0.5}, {0, 0.6, 0, 0.8}};
    for (int tick = 0; tick < 2; tick++) {
        timeval t = at(1700000000, 100000 + 1000 * tick);
        for (int s = 0; s < 3; s++) {
            double p[3] = {pos[s][0] + tick, pos[s][1], pos[s][2]};
            tracker.report_pose(s, t, p, quat[s]);
        }
        double v[3] = {0.1, 0.2, 0.3};
        tracker.report_pose_velocity(0, t, v, quat[0], 1.0);
        tracker.mainloop(); c->mainloop();
    }
    button.set_button(1, 1); button.mainloop(); c->mainloop();
    button.set_button(1, 0); button.mainloop(); c->mainloop();
    analog.channels()[0] = 0.25; analog.channels()[1] = -0.5; analog.channels()[2] = 1.0;
    analog.report(vrpn_CONNECTION_RELIABLE, at(1700000000, 200000)); c->mainloop();
    dial.send(0.05, 0.0, -0.125, at(1700000000, 300000)); c->mainloop();
    text.send_message("capture done", vrpn_TEXT_WARNING, 3, at(1700000000, 400000));
    c->mainloop();
    for (int i = 0; i < 3000 && c->connected(); i++) {
        tracker.mainloop(); button.mainloop(); analog.mainloop(); dial.mainloop(); text.mainloop();
        c->mainloop(); vrpn_SleepMsecs(1);
    }
    fprintf(stderr, "done\n");
    return 0;
}
