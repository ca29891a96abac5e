"""Driver plug-ins: discovery (without importing), loading and checking.

See docs/architecture.md, "Driver plug-ins", for the layout and metadata of a plug-in.
"""

#: The plug-in API this gadgetctl provides; a plug-in declaring another is refused.
PLUGIN_API_VERSION = 1
