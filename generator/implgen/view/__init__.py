"""`implgen view`: the interactive viewer (a local web page, a WebSocket, the C tracer)."""
