"""What a viewer (Foxglove, RViz) shows of a flight: the recording's frames (``/tf``, ``/tf_static``) and markers."""
