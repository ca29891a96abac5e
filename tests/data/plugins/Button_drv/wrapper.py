"""The input-manager side of the button device: a threaded sampler."""

from gadgetctl.input import Digital


class ButtonDevice(Digital):
    ELEMENT_TYPE = "button_device"
    sample_interval = 0.005

    def __init__(self):
        super().__init__()
        self.port = ""
        self.baud = 0
        self.opened = 0
        self.closed = 0
        self._state = 0

    def config(self, access):
        super().config(access)
        self.port = access.string("port")
        self.baud = access.integer("baud")

    def start_sampling(self):
        self.opened += 1

    def sample(self):
        self._state ^= 1
        self.add_digital_sample([self._state])

    def stop_sampling(self):
        self.closed += 1
