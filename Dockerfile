# plotbridge server image. Installs exactly as the README does: scripts/setup-system for the
# Debian packages, then `make setup` for the pinned Python environment.
FROM debian:bookworm-slim

WORKDIR /opt/plotbridge
COPY scripts/setup-system scripts/setup-system
RUN scripts/setup-system run && rm -rf /var/lib/apt/lists/*

COPY . .
RUN make setup firmware sim

ENV PLOTBRIDGE_HOST=0.0.0.0 \
    PLOTBRIDGE_PORT=8000 \
    PLOTBRIDGE_DATA_DIR=/data
VOLUME /data
EXPOSE 8000
# With PLOTBRIDGE_SERIAL set (see docker-compose.yml) it drives a real board,
# otherwise the virtual plotter.
CMD [".venv/bin/plotbridge", "serve"]
