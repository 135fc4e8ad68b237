"""JSON Schemas of the YAML files and the XSD of the element-model XML (data only)."""
