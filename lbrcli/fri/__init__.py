"""KUKA Fast Robot Interface: wire format (protobuf), client session, controller simulator."""
