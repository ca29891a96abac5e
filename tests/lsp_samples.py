"""Configurations the language server tests open (written into tmp_path)."""

HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<?org-vrjuggler-jccl-settings configuration.version="3.0"?>
<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="t">
"""
#: A position proxy (and an alias of it) on the tracker of DEVICES.
PROXIES = """      <position_proxy name="Head" version="1">
         <device>Tracker</device>
         <unit>0</unit>
      </position_proxy>
      <alias name="VJHead" version="1">
         <proxy>Head</proxy>
      </alias>
"""
TRACKERS = """      <dtrack name="Tracker" version="1">
         <receive_port>5000</receive_port>
         <position_filters>
            <position_transform_filter name="Units" version="1">
               <device_units>Feet</device_units>
            </position_transform_filter>
         </position_filters>
      </dtrack>
      <simulated_analog_device name="Sliders" version="2">
         <keyboard_mouse_proxy>Keys</keyboard_mouse_proxy>
      </simulated_analog_device>
      <keyboard_mouse_proxy name="Keys" version="1">
         <device>Keyboard</device>
      </keyboard_mouse_proxy>
      <keyboard_mouse_device name="Keyboard" version="3"/>
"""


def configuration(elements: str, before: str = "") -> str:
    return f"{HEAD}{before}   <elements>\n{elements}   </elements>\n</configuration>\n"


DEVICES = configuration(TRACKERS + PROXIES)
