"""ROS 2 interoperability: standard messages serialised for whole series, MCAP files of logs and plans."""
