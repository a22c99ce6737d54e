"""What the user touches: properties, preferences, operators, panels and the viewport overlay."""
