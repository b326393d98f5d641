"""The data stage of a diagnosis: residuals, the noise floor, localisation, appended rows."""
