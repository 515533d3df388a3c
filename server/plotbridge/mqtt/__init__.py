"""MQTT: Home Assistant discovery, commands from the broker, fleets of bridges.

The one entry point is `service.MqttService`; `api.router` serves the fleet routes;
`settings` reads the options (imported by the command line, so nothing heavy here).
"""
